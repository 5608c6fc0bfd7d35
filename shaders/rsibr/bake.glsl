#version 330 core
// Radiance sphere map of one view (seed 002 §2, §3.1), one fragment per texel:
// the BRDF's lobes (app/envstudio/bake/rsibr/brdfs.py) integrated against the
// environment cube by importance sampling. Each lobe s (integral 1) is sampled
// with u_samples points of a Hammersley set, the same for every texel in the
// frame around its lobe's world axis (so two views give the same value for the
// same world axis, and the map stays smooth), and each sample
// reads the cube at the mip level of its footprint (filtered importance sampling,
// Krivanek and Colbert 2008: lod = 0.5 log2(omega_sample / omega_texel) + 1), so
// the estimate of the a(l) L(l) average converges with few samples. Under a
// constant environment every sample returns the constant: the map is exact.
// Texel (s, t) has the normal n = g_normal(s, t) and mirror r = g_mirror(s, t) of
// §3.3 in the view's frame T (u_frame: world = T local).
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/fresnel.glsl"
#include "common/sampling.glsl"
uniform samplerCube u_environment;
uniform float u_cube_size;     // level-0 face edge, texels
uniform mat3 u_frame;
uniform int u_brdf;            // 0 phong, 1 lambertian, 2 carpaint
uniform int u_samples;
uniform float u_phong_exponent;
uniform float u_coat_f0;
uniform float u_base_exponent;
uniform float u_metallic;
uniform vec3 u_paint;
uniform bool u_irradiance_cube;  // lambertian: u_environment holds E(n)/pi (Miller's map)
in vec2 v_uv;
out vec4 f_color;

vec2 hammersley(int i, int count) {
    uint bits = uint(i);
    bits = (bits << 16u) | (bits >> 16u);
    bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
    bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
    bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
    bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
    return vec2((float(i) + 0.5) / float(count), float(bits) * 2.3283064365386963e-10);
}

// Cube mip level for a sample drawn with density pdf (sr^-1).
float footprint_lod(float pdf) {
    float omega_sample = 1.0 / (float(u_samples) * max(pdf, 1e-8));
    float omega_texel = 4.0 * PI / (6.0 * u_cube_size * u_cube_size);
    return max(0.5 * log2(omega_sample / omega_texel) + 1.0, 0.0);
}

// Average of a(l) L(l) over lobe s: kind 0 Phong about axis (exponent N), 1 cosine
// about axis; with `through`, a = (1 - F_coat(n.l)) above the horizon of n, else a = 1.
vec3 lobe_average(int kind, vec3 axis, float N, vec3 n, bool through) {
    vec3 sum = vec3(0.0);
    for (int i = 0; i < u_samples; ++i) {
        vec2 xi = hammersley(i, u_samples);
        vec3 l = kind == 0 ? sample_phong(axis, N, xi) : sample_cosine(axis, xi);
        float c = max(dot(axis, l), 0.0);
        float pdf = kind == 0 ? phong_lobe(axis, l, N) : c / PI;
        float a = 1.0;
        if (through) {
            float n_dot_l = dot(n, l);
            a = n_dot_l > 0.0 ? 1.0 - schlick_fresnel(u_coat_f0, n_dot_l) : 0.0;
        }
        sum += a * textureLod(u_environment, l, footprint_lod(pdf)).rgb;
    }
    return sum / float(u_samples);
}

void main() {
    vec2 pq = 2.0 * v_uv - 1.0;
    float rho2 = dot(pq, pq);
    if (rho2 > 1.0) pq /= sqrt(rho2);  // outside the disc: the rim's value
    vec3 n_local = vec3(pq, sqrt(max(1.0 - dot(pq, pq), 0.0)));
    vec3 n = normalize(u_frame * n_local);
    vec3 r = normalize(u_frame * vec3(2.0 * n_local.z * n_local.xy, 2.0 * n_local.z * n_local.z - 1.0));
    vec3 v = u_frame[2];
    vec3 value;
    if (u_brdf == 0) {
        value = lobe_average(0, r, u_phong_exponent, n, false);
    } else if (u_brdf == 1) {
        value = u_irradiance_cube ? textureLod(u_environment, n, 0.0).rgb
                                  : lobe_average(1, n, 1.0, n, false);
    } else {
        vec3 glossy = lobe_average(0, r, u_base_exponent, n, true);
        vec3 diffuse = lobe_average(1, n, 1.0, n, true);
        vec3 base = u_paint * mix(diffuse, glossy, u_metallic);
        float coat = schlick_fresnel(u_coat_f0, dot(n, v));
        value = mix(base, textureLod(u_environment, r, 0.0).rgb, coat);
    }
    f_color = vec4(value, 1.0);
}
#endif
