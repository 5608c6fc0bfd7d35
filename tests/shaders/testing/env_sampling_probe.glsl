#version 330 core
// Test probe: each pixel draws one environment sample (common/sampling.glsl)
// and writes its direction and pdf, so tests can compare the GPU sampler with
// core/env_sampling.py.
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/random.glsl"
#include "common/sampling.glsl"
out vec4 f_sample;

void main() {
    vec3 l = sample_environment(random2(uvec2(gl_FragCoord.xy), 0u, 0u));
    f_sample = vec4(l, env_pdf(l));
}
#endif
