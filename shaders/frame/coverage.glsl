#version 330 core
// Which pixels show a reflector: 1 where one is the nearest surface, 0 elsewhere
// (local objects are drawn first, depth only, so they hide what they cover).
#if defined VERTEX_SHADER
#include "common/mesh_vs.glsl"
#elif defined FRAGMENT_SHADER
uniform float u_value;
out vec4 f_color;

void main() {
    f_color = vec4(u_value, 0.0, 0.0, 1.0);
}
#endif
