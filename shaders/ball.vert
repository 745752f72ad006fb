#version 330
// Joint balls and the head: the unit sphere at a joint position with the joint's radius.
in vec3 in_pos;
in vec3 in_normal;
in vec4 in_centre_radius;
in vec4 in_color;
in vec4 in_material;

uniform mat4 u_view_proj;

out vec3 v_pos;
out vec3 v_normal;
out vec4 v_color;
flat out vec4 v_material;
out float v_ring;

void main() {
    vec3 world = in_centre_radius.xyz + in_pos * in_centre_radius.w;
    v_pos = world;
    v_normal = in_normal;
    v_color = in_color;
    v_material = in_material;
    v_ring = 0.0;
    gl_Position = u_view_proj * vec4(world, 1.0);
}
