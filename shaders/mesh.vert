#version 330
// Kit instances: a unit mesh placed by a per-instance model matrix.
in vec3 in_pos;
in vec3 in_normal;
in mat4 in_model;
in vec4 in_color;
in vec4 in_material;

uniform mat4 u_view_proj;

out vec3 v_pos;
out vec3 v_normal;
out vec4 v_color;
flat out vec4 v_material;
out float v_ring;

void main() {
    vec4 world = in_model * vec4(in_pos, 1.0);
    v_pos = world.xyz;
    // Models are rotation * scale, so the inverse transpose is the model over scale squared.
    mat3 m = mat3(in_model);
    vec3 s2 = vec3(dot(m[0], m[0]), dot(m[1], m[1]), dot(m[2], m[2]));
    v_normal = m * (in_normal / s2);
    v_color = in_color;
    v_material = in_material;
    v_ring = length(in_pos.xy);
    gl_Position = u_view_proj * world;
}
