#version 330
// Skinned avatar: linear blend skinning with the 24 skin matrices (world * inverse(bind)) of
// the frame's pose; up to four influences per vertex, renormalised here so a loader's rounding
// never shrinks a vertex towards the origin. Transform feedback reads v_pos back in tests.
// in_offset is the face's shapes summed for this frame (bind pose, metres; zero without).
in vec3 in_pos;
in vec3 in_offset;
in vec3 in_normal;
in vec2 in_uv;
in vec4 in_joints;
in vec4 in_weights;

uniform mat4 u_view_proj;
uniform mat4 u_skin[24];

out vec3 v_pos;
out vec3 v_normal;
out vec2 v_uv;

void main() {
    vec4 w = in_weights;
    float total = w.x + w.y + w.z + w.w;
    w = total > 1e-6 ? w / total : vec4(1.0, 0.0, 0.0, 0.0);
    ivec4 j = ivec4(in_joints + 0.5);
    mat4 m = w.x * u_skin[j.x] + w.y * u_skin[j.y] + w.z * u_skin[j.z] + w.w * u_skin[j.w];
    vec4 world = m * vec4(in_pos + in_offset, 1.0);
    v_pos = world.xyz;
    // Skin matrices are rotations plus translations (blended), so mat3(m) turns normals.
    v_normal = mat3(m) * in_normal;
    v_uv = in_uv;
    gl_Position = u_view_proj * world;
}
