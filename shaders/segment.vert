#version 330
// Body capsules and sticks: the unit cylinder (radius 1, z 0..1) stretched from joint a to b.
// The basis is built here so the pose array goes to the GPU as joint positions, not matrices.
in vec3 in_pos;
in vec3 in_normal;
in vec3 in_a;
in vec3 in_b;
in float in_radius;
in vec4 in_color;
in vec4 in_material;

uniform mat4 u_view_proj;

out vec3 v_pos;
out vec3 v_normal;
out vec4 v_color;
flat out vec4 v_material;
out float v_ring;

void main() {
    vec3 d = in_b - in_a;
    float len = length(d);
    vec3 z = len > 1e-6 ? d / len : vec3(0.0, 0.0, 1.0);
    vec3 helper = abs(z.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    vec3 x = normalize(cross(helper, z));
    vec3 y = cross(z, x);
    vec3 world = in_a + (x * in_pos.x + y * in_pos.y) * in_radius + z * (in_pos.z * len);
    v_pos = world;
    v_normal = x * in_normal.x + y * in_normal.y + z * in_normal.z;
    v_color = in_color;
    v_material = in_material;
    v_ring = 0.0;
    gl_Position = u_view_proj * vec4(world, 1.0);
}
