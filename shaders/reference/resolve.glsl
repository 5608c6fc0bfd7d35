#version 330 core
// Method `reference`, resolve pass: draws the reflectors (depth-tested against
// the frame's local objects) with the accumulated mean sum / count.
#if defined VERTEX_SHADER
#include "common/mesh_vs.glsl"
#elif defined FRAGMENT_SHADER
uniform sampler2D u_sum;
out vec4 f_color;

void main() {
    vec4 sum = texelFetch(u_sum, ivec2(gl_FragCoord.xy), 0);
    f_color = vec4(sum.a > 0.0 ? sum.rgb / sum.a : vec3(0.0), 1.0);
}
#endif
