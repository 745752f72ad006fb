#version 330
#include "lighting.glsl"

in vec3 v_pos;
in vec3 v_normal;
in vec4 v_color;
flat in vec4 v_material;
in float v_ring;

out vec4 f_color;

void main() {
    vec3 n = normalize(v_normal);
    if (!gl_FrontFacing) {
        n = -n;
    }
    vec3 c = shade(v_pos, n, v_color.rgb, v_material, v_color.a, v_ring);
    f_color = vec4(with_glow(display(c), v_color.a), 1.0);
}
