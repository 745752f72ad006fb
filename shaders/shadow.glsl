// The key light's shadow: the depth the key spot sees (a depth texture rendered from the light
// each frame, compared in hardware: four bilinear 2x2 percentage-closer lookups) at this
// surface point. 1 is lit, 0 in shadow; the lookup is offset along the normal against acne. Off
// (u_shadow_on = 0) every point is lit, and the map is never sampled.
uniform sampler2DShadow u_shadow_map;
uniform mat4 u_light_vp;
uniform int u_shadow_on;

float key_shadow(vec3 pos, vec3 n) {
    if (u_shadow_on == 0) {
        return 1.0;
    }
    vec4 lp = u_light_vp * vec4(pos + n * 0.012, 1.0);
    vec3 p = lp.xyz / lp.w * 0.5 + 0.5;
    if (p.x <= 0.0 || p.x >= 1.0 || p.y <= 0.0 || p.y >= 1.0 || p.z >= 1.0) {
        return 1.0;
    }
    // four hardware-filtered taps on a rotated grid, 0.75 texel out: soft, stair-free edges
    vec2 t = 0.75 / vec2(textureSize(u_shadow_map, 0));
    float z = p.z - 0.0016;
    return 0.25 * (texture(u_shadow_map, vec3(p.xy + vec2(-0.4, -1.0) * t, z))
                 + texture(u_shadow_map, vec3(p.xy + vec2(1.0, -0.4) * t, z))
                 + texture(u_shadow_map, vec3(p.xy + vec2(0.4, 1.0) * t, z))
                 + texture(u_shadow_map, vec3(p.xy + vec2(-1.0, 0.4) * t, z)));
}
