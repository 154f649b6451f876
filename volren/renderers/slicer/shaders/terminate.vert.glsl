#version 330
// One triangle covering the viewport, at the near depth (0).
void main() {
    vec2 corner = vec2(float((gl_VertexID & 1) * 4 - 1), float((gl_VertexID >> 1) * 4 - 1));
    gl_Position = vec4(corner, -1.0, 1.0);
}
