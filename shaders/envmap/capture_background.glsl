#version 330 core
// Dynamic cube capture (envmap/dynamic_cube.py), the environment at infinity:
// the six faces of level 0 side by side in one 6n x n strip, face f in columns
// [f n, (f + 1) n); each pixel looks up the environment (level 0) along the
// direction of its face texel.
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/cubemap.glsl"
uniform samplerCube u_environment;
uniform int u_size;  // n
out vec4 f_color;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    int face = pixel.x / u_size;
    vec2 uv = (vec2(pixel.x - face * u_size, pixel.y) + 0.5) / float(u_size);
    f_color = vec4(textureLod(u_environment, cube_face_direction(face, uv), 0.0).rgb, 1.0);
}
#endif
