#version 330
// RGBA frame -> the Cb and Cr planes of I420, drawn over target rows H .. 3H/2 - 1 below the
// luma plane (see i420_luma.frag for the packing: four bytes per fragment, so W must be a
// multiple of 8). A fragment works out its byte offset past the luma plane, which plane that
// is, and the chroma row and column; offsets rather than rows keep any height right, even where
// the Cb plane ends mid-row. Each chroma sample is the mean of its 2x2 block, one bilinear fetch
// at the point where the four pixel centres meet (the conversion is linear, so averaging RGB
// first equals averaging Cb/Cr after). The arithmetic is float: exact below 2^24, and far
// cheaper on llvmpipe than integer division, which it does lane by lane.
#include "bt709.glsl"

uniform sampler2D u_image;  // linear filtering
uniform ivec2 u_size;  // the image's W, H

out vec4 f_bytes;

void main() {
    vec2 size = vec2(u_size);
    float half_w = 0.5 * size.x;
    float plane = half_w * 0.5 * size.y;
    float offset = (floor(gl_FragCoord.y) - size.y) * size.x + 4.0 * floor(gl_FragCoord.x);
    bool cr = offset >= plane;
    if (cr) {
        offset -= plane;
    }
    float row = floor((offset + 0.5) / half_w);
    float col = offset - row * half_w;
    // In GL coordinates the block of chroma (col, row) spans image rows H-2-2row .. H-1-2row.
    float y = (size.y - 1.0 - 2.0 * row) / size.y;
    float x = (2.0 * col + 1.0) / size.x;
    float dx = 2.0 / size.x;
    f_bytes = vec4(chroma_byte(texture(u_image, vec2(x, y)).rgb, cr),
                   chroma_byte(texture(u_image, vec2(x + dx, y)).rgb, cr),
                   chroma_byte(texture(u_image, vec2(x + 2.0 * dx, y)).rgb, cr),
                   chroma_byte(texture(u_image, vec2(x + 3.0 * dx, y)).rgb, cr));
}
