// Stage lighting shared by every lit surface: a warm key spot from the front of house, a cool
// rim light from behind and above (it draws the silhouette against the dark hall), a dim
// hemisphere fill, metallic reflection of a fake overhead rig, and the hit highlight. The key
// light casts shadows (shadow.glsl); rim and fill do not.
#include "shadow.glsl"
uniform vec3 u_eye;
uniform vec3 u_key_pos;
uniform vec3 u_key_color;
uniform vec3 u_rim_dir;
uniform vec3 u_rim_color;

const vec3 HIGHLIGHT_COLOR = vec3(1.0, 0.78, 0.42);

vec3 shade(vec3 pos, vec3 n, vec3 base, vec4 material, float highlight, float ring_r) {
    float metal = material.x;
    float shininess = material.y;
    int kind = int(material.z + 0.5);
    vec3 v = normalize(u_eye - pos);
    if (kind == 2) {
        // Cymbal: lathe grooves as fine concentric rings of brightness.
        base *= 0.86 + 0.14 * sin(ring_r * 90.0);
    }
    if (kind == 3 && material.w > 0.5) {
        // Resonant kick head: a coloured logo band.
        base = mix(base, vec3(0.85, 0.62, 0.26), step(0.55, ring_r) * step(ring_r, 0.68));
    }
    vec3 l = normalize(u_key_pos - pos);
    vec3 h = normalize(l + v);
    float ndl = max(dot(n, l), 0.0);
    // Schlick's rational stand-in for pow(n.h, shininess): one division instead of exp/log.
    float ndh = max(dot(n, h), 0.0);
    float spec = ndh / (shininess - shininess * ndh + ndh) * step(0.0, ndl);
    vec3 spec_color = mix(vec3(0.25), base, metal);
    vec3 diffuse = base * (1.0 - 0.75 * metal);
    float lit = ndl > 0.0 ? key_shadow(pos, n) : 1.0;
    vec3 color = (diffuse * ndl * u_key_color + spec_color * spec * u_key_color * 1.2) * lit;
    // Rim: strongest where the surface turns away from the viewer and faces the rim light.
    float edge = 1.0 - max(dot(n, v), 0.0);
    edge *= edge * edge;
    color += u_rim_color * mix(vec3(1.0), base * 1.4, metal) * edge * max(dot(n, u_rim_dir), 0.0);
    // Fill: a dim sky above, darker floor bounce below.
    color += base * mix(vec3(0.035, 0.03, 0.03), vec3(0.09, 0.09, 0.12), 0.5 + 0.5 * n.z);
    // Metals reflect the lighting rig: bright above the horizon, dark below.
    vec3 r = reflect(-v, n);
    color += metal * base * 0.45 * smoothstep(-0.1, 0.7, r.z);
    color += highlight * (HIGHLIGHT_COLOR * 0.85 + base * 0.25);
    return color;
}
