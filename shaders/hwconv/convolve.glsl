#version 330 core
// Method `hwconv`, seed 004 section 5.2 steps 6-8: one face of the dual-paraboloid
// map, shrunk by s (read at mip level log2 s of the source, "uses mip-mapping"),
// convolved with the Phong lobe sampled into a (2K+1)^2 kernel - the fragment pass
// that stands in for OpenGL's imaging-subset convolution. One fragment per texel of
// the shrunk face; taps outside the face are clamped to its edge (the border keeps
// them off the disc, FilterPlan.check_border). The weights (radii.kernel_weights,
// summing to 1) are uniforms, so a change of N or epsilon never recompiles.
//
// Defines: MAX_KERNEL, the largest 2K+1 the weight array holds.
// Uniforms:
//   u_source   sampler2DArray, the dual paraboloid with its mip chain (layers 0, 1)
//   u_face     layer to filter
//   u_level    mip level log2 s
//   u_radius   K, taps each side of the centre
//   u_weights  (2K+1)^2 weights, row-major from (-K, -K)
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
uniform sampler2DArray u_source;
uniform int u_face;
uniform int u_level;
uniform int u_radius;
uniform float u_weights[MAX_KERNEL * MAX_KERNEL];
out vec4 f_color;

void main() {
    ivec2 texel = ivec2(gl_FragCoord.xy);
    ivec2 last = textureSize(u_source, u_level).xy - 1;
    int width = 2 * u_radius + 1;
    vec3 sum = vec3(0.0);
    for (int j = -u_radius; j <= u_radius; ++j) {
        for (int i = -u_radius; i <= u_radius; ++i) {
            float w = u_weights[(j + u_radius) * width + (i + u_radius)];
            if (w > 0.0) {
                ivec2 tap = clamp(texel + ivec2(i, j), ivec2(0), last);
                sum += w * texelFetch(u_source, ivec3(tap, u_face), u_level).rgb;
            }
        }
    }
    f_color = vec4(sum, 1.0);
}
#endif
