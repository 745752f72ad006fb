#version 330
// Shadow-map pass: depth only, the colour is never written.
void main() {
}
