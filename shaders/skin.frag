#version 330
#include "lighting.glsl"
// Avatar surfaces: base colour factor times an optional base-colour texture (both taken as
// sRGB-encoded, decoded to linear by the stage lighting); glTF alpha modes (0 opaque, 1 mask:
// discard under the cutoff, 2 blend: the renderer draws these after the opaque ones with
// blending on); shading 0 is the stage lighting of every lit surface (u_kind 4: skin, 0:
// cloth and the rest), 1 is toon (MToon drawn as two bands of the key light plus the rim).
in vec3 v_pos;
in vec3 v_normal;
in vec2 v_uv;

uniform vec4 u_base_color;
uniform sampler2D u_texture;
uniform bool u_has_texture;
uniform int u_alpha_mode;
uniform float u_alpha_cutoff;
uniform int u_shading;
uniform float u_shininess;
uniform int u_kind;

out vec4 f_color;

const float FACE_FILL = 0.18;

void main() {
    vec4 base = u_base_color;
    if (u_has_texture) {
        base *= texture(u_texture, v_uv);
    }
    if (u_alpha_mode == 1 && base.a < u_alpha_cutoff) {
        discard;
    }
    vec3 n = normalize(v_normal);
    if (!gl_FrontFacing) {
        n = -n;
    }
    vec3 v = normalize(u_eye - v_pos);
    vec3 lin = linear_of(base.rgb);
    vec3 c;
    if (u_shading == 1) {
        vec3 l = normalize(u_key_pos - v_pos);
        float band = smoothstep(0.05, 0.12, dot(n, l)) * key_shadow(v_pos, n);
        float edge = pow(1.0 - max(dot(n, v), 0.0), 3.0);
        c = lin * (mix(u_fill_color * 0.5 + ambient(n) * 2.0, u_key_color, band) + u_wash_color * 0.3)
            + u_rim_color * edge * max(dot(n, u_rim_dir), 0.0) * 0.4;
    } else {
        c = shade(v_pos, n, base.rgb, vec4(0.0, u_shininess, float(u_kind), 0.0), 0.0, 0.0);
    }
    // a soft follow spot from the viewer's side: the face stays readable when the drummer
    // looks down at the kit, under a key light from high in front
    c += lin * FACE_FILL * u_key_color * max(dot(n, v), 0.0);
    f_color = vec4(display(c), u_alpha_mode == 2 ? base.a : 1.0);
}
