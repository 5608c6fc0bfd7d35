#version 330 core
// Method `hwconv`, kernel = exact (past seed 004 section 5.2): the shift-variant
// kernel the d^2 blend of maps S and L approximates. Each texel of the target face
// is the normalised sum over a (2K+1)^2 window of the source's mip level u_level of
//     w = <r, l>^N  (0 where below epsilon)  *  4 / (1 + s^2 + t^2)^2,
// r the target texel's direction, l the tap's (beyond the rim: the other hemisphere,
// core.paraboloid), the second factor the paraboloid's solid-angle element per unit
// (s, t) area (the taps are equally spaced in (s, t)). The lobe is thus the same on
// the sphere at every texel, the rim included. N and epsilon are uniforms.
//
// Uniforms:
//   u_source       sampler2DArray, the dual paraboloid with its mip chain
//   u_face         layer to filter (0 front, 1 back)
//   u_level        mip level the taps read (the large kernel's, log2 s_l)
//   u_radius       K, taps each side of the centre
//   u_size         face size n of level 0 in texels (border included)
//   u_border       border B of level 0 in texels
//   u_target_size  texels across the target face
//   u_exponent     N
//   u_epsilon      epsilon
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/paraboloid.glsl"
uniform sampler2DArray u_source;
uniform int u_face;
uniform int u_level;
uniform int u_radius;
uniform float u_size;
uniform float u_border;
uniform float u_target_size;
uniform float u_exponent;
uniform float u_epsilon;
out vec4 f_color;

void main() {
    vec2 uv = gl_FragCoord.xy / u_target_size;
    vec3 r = paraboloid_direction(u_face, uv, u_size, u_border);
    ivec2 levels = textureSize(u_source, u_level).xy;
    vec2 level_size = vec2(levels);
    ivec2 centre = ivec2(floor(uv * level_size));
    float scale = u_size / (u_size - 2.0 * u_border);
    vec3 sum = vec3(0.0);
    float total = 0.0;
    for (int j = -u_radius; j <= u_radius; ++j) {
        for (int i = -u_radius; i <= u_radius; ++i) {
            ivec2 tap = centre + ivec2(i, j);
            if (any(lessThan(tap, ivec2(0))) || any(greaterThanEqual(tap, levels))) {
                continue;
            }
            vec2 tap_uv = (vec2(tap) + 0.5) / level_size;
            vec3 l = paraboloid_direction(u_face, tap_uv, u_size, u_border);
            float c = max(dot(r, l), 0.0);
            float lobe = pow(c, u_exponent);
            if (lobe < u_epsilon) {
                continue;
            }
            vec2 st = (2.0 * tap_uv - 1.0) * scale;
            float k = 1.0 + dot(st, st);
            float w = lobe * 4.0 / (k * k);
            sum += w * texelFetch(u_source, ivec3(tap, u_face), u_level).rgb;
            total += w;
        }
    }
    f_color = vec4(total > 0.0 ? sum / total : vec3(0.0), 1.0);
}
#endif
