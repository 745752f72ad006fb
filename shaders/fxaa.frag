#version 330
// Fast approximate anti-aliasing: one full-screen pass over the finished frame (Renderer's
// fxaa). Where the luma of the four diagonal neighbours spans more than a threshold, the pixel
// is on an edge: the edge's direction comes from the neighbours' luma gradient, and the pixel
// is replaced by samples taken along the edge (bilinear), two near or four reaching further;
// the wider blend is kept unless its luma leaves the neighbourhood's range (a corner or thin
// detail it would smear). Alpha is filtered with the colour, so a transparent frame's
// silhouette is smoothed too. Costs about one texture fetch pass, where multisampling on a
// CPU rasterizer costs several times the frame.

uniform sampler2D u_image;
uniform vec2 u_texel;  // 1 / frame size in pixels

out vec4 f_color;

const float EDGE_MIN = 1.0 / 24.0;  // darkest contrast treated as an edge
const float EDGE_REL = 1.0 / 8.0;   // ... or this fraction of the local brightest luma
const float SPAN = 8.0;             // longest reach along an edge, pixels

float luma(vec3 c) { return dot(c, vec3(0.299, 0.587, 0.114)); }

void main() {
    vec2 uv = gl_FragCoord.xy * u_texel;
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 top = textureSize(u_image, 0) - 1;
    vec4 centre = texelFetch(u_image, p, 0);
    float m = luma(centre.rgb);
    // unfiltered neighbours (cheaper than filtered taps on a CPU rasterizer)
    float nw = luma(texelFetch(u_image, clamp(p + ivec2(-1, 1), ivec2(0), top), 0).rgb);
    float ne = luma(texelFetch(u_image, clamp(p + ivec2(1, 1), ivec2(0), top), 0).rgb);
    float sw = luma(texelFetch(u_image, clamp(p + ivec2(-1, -1), ivec2(0), top), 0).rgb);
    float se = luma(texelFetch(u_image, clamp(p + ivec2(1, -1), ivec2(0), top), 0).rgb);
    float lo = min(m, min(min(nw, ne), min(sw, se)));
    float hi = max(m, max(max(nw, ne), max(sw, se)));
    if (hi - lo < max(EDGE_MIN, hi * EDGE_REL)) {
        f_color = centre;
        return;
    }
    vec2 dir = vec2((sw + se) - (nw + ne), (nw + sw) - (ne + se));
    float damp = max(0.03125 * (nw + ne + sw + se), 1.0 / 128.0);
    dir = clamp(dir / (min(abs(dir.x), abs(dir.y)) + damp), -SPAN, SPAN) * u_texel;
    vec4 near = 0.5 * (texture(u_image, uv - dir / 6.0) + texture(u_image, uv + dir / 6.0));
    vec4 wide = 0.5 * near
        + 0.25 * (texture(u_image, uv - dir * 0.5) + texture(u_image, uv + dir * 0.5));
    float lw = luma(wide.rgb);
    f_color = (lw < lo || lw > hi) ? near : wide;
}
