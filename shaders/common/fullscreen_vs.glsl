// Full-screen triangle from gl_VertexID (no vertex buffers). Include in a
// VERTEX_SHADER section; defines main() and the varying v_uv in [0, 1]^2,
// with v_uv = (0, 0) at the lower-left of the framebuffer.
out vec2 v_uv;

void main() {
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    v_uv = p;
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
