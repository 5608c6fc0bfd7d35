// Irradiance E(n) from SH plus cap lights (seed 000 section 4.1, eq. 12, and past it:
// core.sh_lights), the diffuse term of `kautz` and `mirror` (shading/sh_irradiance.py).
// The uniform block ShIrradiance, which core.sh_lights.DiffuseLighting.block (static
// environments) or prefilter/sh_reduce.glsl (dynamic ones, on the GPU) fills:
//   u_sh[i]              vec4(A_l L_i, 0): SH coefficients already convolved with the
//                        clamped cosine (seed 000 eq. 12), storage order of
//                        common/sh_bands.glsl
//   u_light_direction[k] vec4(unit direction, sin^2 alpha) of cap light k
//   u_light_rgb[k]       vec4(moment magnitude per channel, 0)
// E(n) = sum_i u_sh[i] Y_i(n) + sum_k rgb_k cap_irradiance(n . dir_k, sin^2 alpha_k).
// Defines: SH_COEFFICIENTS (9, 25, 49), LIGHTS (0 .. 32).
#include "common/sh_bands.glsl"
#include "common/cap_light.glsl"

layout(std140) uniform ShIrradiance {
    vec4 u_sh[SH_COUNT];
#if LIGHTS > 0
    vec4 u_light_direction[LIGHTS];
    vec4 u_light_rgb[LIGHTS];
#endif
};

vec3 sh_irradiance(vec3 n) {
    float y[SH_COUNT];
    sh_bands_basis(n, y);
    vec3 e = vec3(0.0);
    for (int i = 0; i < SH_COUNT; ++i) {
        e += u_sh[i].rgb * y[i];
    }
#if LIGHTS > 0
    for (int k = 0; k < LIGHTS; ++k) {
        vec4 light = u_light_direction[k];
        e += u_light_rgb[k].rgb * cap_irradiance(dot(n, light.xyz), light.w);
    }
#endif
    return max(e, vec3(0.0));
}

// E(n) where k_d has a channel above 0, else 0: a black diffuse term costs no SH evaluation
// (a uniform branch; `mirror` is the bench's baseline, and k_d = 0 its common case).
vec3 sh_irradiance_if(vec3 kd, vec3 n) {
    return any(greaterThan(kd, vec3(0.0))) ? sh_irradiance(n) : vec3(0.0);
}
