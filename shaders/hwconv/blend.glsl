#version 330 core
// Method `hwconv`, seed 004 section 5.2 steps 10-12: one face of the blended map,
//   E = (1 - w) S + w L,  w = min(d^2, 1),
// d the distance of the texel from the paraboloid's centre in units of the disc's
// radius (0 % of L at the centre, 25 % at d = 0.5). S and L are read bilinearly
// from their shrunk faces; the result has the full size (one fragment per texel).
//
// Uniforms:
//   u_small, u_large  sampler2D, this face of maps S and L
//   u_size            face size n in texels (border included)
//   u_border          border B in texels
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
uniform sampler2D u_small;
uniform sampler2D u_large;
uniform float u_size;
uniform float u_border;
out vec4 f_color;

void main() {
    vec2 uv = gl_FragCoord.xy / u_size;
    vec2 st = (2.0 * uv - 1.0) * u_size / (u_size - 2.0 * u_border);
    float w = min(dot(st, st), 1.0);
    vec3 small = textureLod(u_small, uv, 0.0).rgb;
    vec3 large = textureLod(u_large, uv, 0.0).rgb;
    f_color = vec4(mix(small, large, w), 1.0);
}
#endif
