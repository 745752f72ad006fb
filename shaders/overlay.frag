#version 330
// An RGBA overlay image (the score strip, the joint-angle graph) over the frame already drawn.
// Drawn with fullscreen.vert into a viewport that is exactly the overlay's rectangle, blended
// with straight alpha (Renderer.draw_overlay). The image is uploaded top row first, as numpy
// holds it, so rows are flipped here; with nearest filtering and a rectangle of the image's
// size, each fragment reads exactly its own texel.

uniform sampler2D u_image;
uniform vec4 u_rect;  // x, y of the bottom-left corner and w, h, in framebuffer pixels

out vec4 f_color;

void main() {
    vec2 uv = (gl_FragCoord.xy - u_rect.xy) / u_rect.zw;
    f_color = texture(u_image, vec2(uv.x, 1.0 - uv.y));
}
