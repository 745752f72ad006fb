// Show lighting shared by every lit surface, in linear light (livedrummer/render/lights.py is
// the rig: key, fill, rim and wash, each a colour times intensity and a direction towards the
// light, and the ambient sky and ground). Base colours arrive sRGB-encoded and are decoded
// here; display() tone-maps the sum (a fitted filmic curve, so a bright key rolls off instead
// of clipping) and encodes sRGB for the 8-bit frame. The key casts shadows (shadow.glsl).
// Materials by kind: 0 plain (lacquer, chrome, cloth: metalness and shininess decide), 2
// cymbal (brass with lathe grooves), 3 drum head, 4 skin (wrapped diffuse, a warm sheen).
#include "shadow.glsl"
uniform vec3 u_eye;
uniform vec3 u_key_pos;
uniform vec3 u_key_color;
uniform vec3 u_fill_dir;
uniform vec3 u_fill_color;
uniform vec3 u_rim_dir;
uniform vec3 u_rim_color;
uniform vec3 u_wash_dir;
uniform vec3 u_wash_color;
uniform vec3 u_sky;
uniform vec3 u_ground;
uniform float u_exposure;

const vec3 HIGHLIGHT_COLOR = vec3(1.0, 0.60, 0.20);
const vec3 GLOW_DISPLAY = vec3(0.60, 0.50, 0.35);

vec3 linear_of(vec3 srgb) { return pow(srgb, vec3(2.2)); }

vec3 display(vec3 c) {
    vec3 x = max(c * u_exposure, 0.0);
    x = clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    return pow(x, vec3(1.0 / 2.2));
}

// The ambient environment: sky above, floor bounce below.
vec3 ambient(vec3 n) { return mix(u_ground, u_sky, 0.5 + 0.5 * n.z); }

vec3 shade(vec3 pos, vec3 n, vec3 base_srgb, vec4 material, float highlight, float ring_r) {
    float metal = material.x;
    float shininess = material.y;
    int kind = int(material.z + 0.5);
    vec3 base = linear_of(base_srgb);
    vec3 v = normalize(u_eye - pos);
    if (kind == 2) {
        base *= 0.86 + 0.14 * sin(ring_r * 90.0);
    }
    if (kind == 3) {
        // a coated head reads off-white under the wash, leaving headroom for its hit glow
        base *= 0.62;
    }
    if (kind == 3 && material.w > 0.5) {
        base = mix(base, vec3(0.70, 0.36, 0.06), step(0.55, ring_r) * step(ring_r, 0.68));
    }
    vec3 l = normalize(u_key_pos - pos);
    vec3 h = normalize(l + v);
    float ndl = dot(n, l);
    // skin wraps the key round its terminator (light under the surface); others stop at 0
    float wrap = kind == 4 ? 0.35 : 0.0;
    float diff = max((ndl + wrap) / (1.0 + wrap), 0.0);
    float ndh = max(dot(n, h), 0.0);
    // Schlick's rational stand-in for pow(n.h, shininess): one division instead of exp/log
    float spec = ndh / (shininess - shininess * ndh + ndh) * step(0.0, ndl);
    // dielectrics reflect 4 % white (a lacquer's clear coat), metals their own colour
    vec3 spec_color = mix(vec3(0.04 * min(shininess, 60.0) / 12.0), base * 1.2, metal);
    vec3 diffuse = base * (1.0 - 0.85 * metal);
    float lit = ndl > 0.0 ? key_shadow(pos, n) : 1.0;
    vec3 color = (diffuse * diff + spec_color * spec) * u_key_color * lit;
    // fill and wash: soft half-wrapped diffuse, no shadow, no highlight
    color += diffuse * u_fill_color * max(0.6 * dot(n, u_fill_dir) + 0.4, 0.0);
    color += diffuse * u_wash_color * max(0.5 * dot(n, u_wash_dir) + 0.5, 0.0) * 0.6;
    // rim: edges turned away from the viewer and towards the back light
    float edge = 1.0 - max(dot(n, v), 0.0);
    edge *= edge;
    color += u_rim_color * (base * mix(0.8, 1.5, metal) + 0.04) * edge * max(dot(n, u_rim_dir) + 0.3, 0.0);
    color += diffuse * ambient(n);
    // metals mirror the environment: the lit rig above the horizon, the dark hall below
    vec3 r = reflect(-v, n);
    color += metal * base * (u_sky * 3.0 + (u_key_color + u_wash_color) * 0.12) * (0.3 + 0.7 * smoothstep(-0.2, 0.8, r.z));
    color += highlight * (HIGHLIGHT_COLOR * 2.0 + base * 0.8);
    return color;
}

// A struck piece's glow on the displayed colour, after tone mapping: added in linear light
// alone, a glow on a surface the key and the wash already light brightly would be rolled off
// by the filmic shoulder and barely show.
vec3 with_glow(vec3 shown, float highlight) {
    return min(shown + highlight * GLOW_DISPLAY, vec3(1.0));
}
