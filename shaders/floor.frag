#version 330
// The stage floor, cheaper than lit.frag because it covers most of the frame: planks lit in
// linear light by the key (with the drummer's and the kit's shadows) and the wash in a pool
// round the kit that fades into the dark hall (no specular, no rim), plus the ambient ground
// term; tone-mapped and sRGB-encoded as every lit surface (lighting.glsl). On a stage each
// floor is drawn only in its own drummer's cell (floor_cell.glsl). The rim fades to
// transparent.
#include "lighting.glsl"
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
    float pool = 1.0 - smoothstep(0.3, u_stage_radius, d);
    pool *= 2.0 - pool;
    float plank = 0.93 + 0.07 * step(0.5, fract(v_pos.x * 6.0));
    vec3 base = linear_of(v_color.rgb) * plank;
    float key = max(dot(normalize(u_key_pos - v_pos), vec3(0.0, 0.0, 1.0)), 0.0);
    vec3 light = u_key_color * key * mix(0.4, 1.0, key_shadow(v_pos, vec3(0.0, 0.0, 1.0)))
        + u_wash_color * max(u_wash_dir.z, 0.0);
    vec3 c = base * (light * pool + u_sky * 0.5);
    // the rim fades out (blended), into the hall, a colour, an image or alpha 0 alike
    f_color = vec4(display(c), 1.0 - smoothstep(0.85 * u_stage_radius, u_stage_radius, d));
}
