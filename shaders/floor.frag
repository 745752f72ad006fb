#version 330
// The stage floor, cheaper than lit.frag because it covers most of the frame: planks, and a
// pool of key light around the kit that fades into the dark hall (no specular, no rim), in
// which the drummer and the kit cast the key light's shadow. The rim fades to transparent.
#include "shadow.glsl"
#include "floor_cell.glsl"
uniform vec3 u_stage_centre;
uniform float u_stage_radius;

in vec3 v_pos;
in vec3 v_normal;
in vec4 v_color;
flat in vec4 v_material;
in float v_ring;

out vec4 f_color;

void main() {
    if (outside_floor_cell(v_pos.xy, u_stage_centre.xy)) {
        discard;
    }
    float d = length(v_pos.xy - u_stage_centre.xy);
    float pool = 1.0 - smoothstep(0.4, u_stage_radius, d);
    pool *= mix(0.45, 1.0, key_shadow(v_pos, vec3(0.0, 0.0, 1.0)));
    float plank = 0.88 + 0.12 * step(0.5, fract(v_pos.x * 6.0));
    vec3 c = v_color.rgb * plank * (0.12 + 1.25 * pool * pool) * vec3(1.05, 0.95, 0.85);
    // the rim fades out (blended), into the hall, a colour, an image or alpha 0 alike
    f_color = vec4(c, 1.0 - smoothstep(0.85 * u_stage_radius, u_stage_radius, d));
}
