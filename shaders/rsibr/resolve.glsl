#version 330 core
// The accumulation's return (seed 002 §4, glAccum(GL_RETURN, 1 / sum a_i)): each
// texel of the blend divided by its summed weight (alpha), which is sum a_i
// where no source is faded.
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
uniform sampler2D u_accumulation;
in vec2 v_uv;
out vec4 f_color;
void main() {
    vec4 sum = texelFetch(u_accumulation, ivec2(gl_FragCoord.xy), 0);
    f_color = vec4(sum.a > 0.0 ? sum.rgb / sum.a : vec3(0.0), 1.0);
}
#endif
