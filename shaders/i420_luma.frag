#version 330
// RGBA frame -> the luma plane of I420 (the first of two passes; i420_chroma.frag is the
// second). See Renderer.read_i420: the target is RGBA8, W/4 texels wide, and each fragment
// writes four neighbouring luma bytes, because llvmpipe's cost is mostly per fragment, not per
// texture fetch (four bytes a fragment is about twice as fast as one). Target row r is image
// row H-1-r: the flip from OpenGL's bottom-up rows to the encoder's top-down ones is free here.
#include "bt709.glsl"

uniform sampler2D u_image;  // nearest filtering
uniform ivec2 u_size;  // the image's W, H

out vec4 f_bytes;

void main() {
    vec2 size = vec2(u_size);
    float y = (size.y - gl_FragCoord.y) / size.y;  // row H-1-r, at its texel centre
    float x = (4.0 * floor(gl_FragCoord.x) + 0.5) / size.x;
    float dx = 1.0 / size.x;
    f_bytes = vec4(luma_byte(texture(u_image, vec2(x, y)).rgb),
                   luma_byte(texture(u_image, vec2(x + dx, y)).rgb),
                   luma_byte(texture(u_image, vec2(x + 2.0 * dx, y)).rgb),
                   luma_byte(texture(u_image, vec2(x + 3.0 * dx, y)).rgb));
}
