#version 330
// One triangle that covers the whole viewport, built from gl_VertexID, so a full-screen pass
// needs no vertex buffer: ids 0, 1, 2 give (-1,-1), (3,-1), (-1,3) in clip space.
void main() {
    vec2 p = vec2(float((gl_VertexID & 1) * 4 - 1), float((gl_VertexID & 2) * 2 - 1));
    gl_Position = vec4(p, 0.0, 1.0);
}
