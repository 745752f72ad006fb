// BT.709 Y'CbCr in limited ("TV") range, as fractions of 255 for an 8-bit UNORM target:
// luma 16..235, chroma 16..240 centred on 128. What the encoder's stream metadata declares.
const vec3 LUMA = vec3(0.2126, 0.7152, 0.0722);  // Kr, Kg, Kb

float luma_byte(vec3 rgb) {
    return (16.0 + 219.0 * dot(LUMA, rgb)) / 255.0;
}

// cr false: Cb, from B - Y'; cr true: Cr, from R - Y'.
float chroma_byte(vec3 rgb, bool cr) {
    float y = dot(LUMA, rgb);
    float d = cr ? (rgb.r - y) / 1.5748 : (rgb.b - y) / 1.8556;
    return (128.0 + 224.0 * d) / 255.0;
}
