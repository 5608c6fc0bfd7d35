#version 330 core
// Method `parallax`: a parallax-corrected cube map (Lagarde and Zanuttini, SIGGRAPH 2012
// talk "Local image-based lighting with parallax-corrected cubemaps").
//   lookup   the reflection ray p + t r meets the proxy at x = p + t r
//            (parallax/proxy.glsl); the cube captured at the probe c is read towards
//            d = x - c instead of along r
//   glossy   PHONG_CHAIN 1: the probe cube's Phong-prefiltered mip chain
//            (prefilter/chain_gpu.py gpu_phong_cube_chain, the cube's own face edge n),
//            level k holding N_k = (n / 2^(k+1))^2, read at the fractional level
//            log2(n) - 1 - log2(N) / 2 (trilinear: log-linear in N between levels);
//            PHONG_CHAIN 0: the cube's box-filtered mips at the level that looks like the
//            lobe by prefilter/glossiness.py's fit, b = W(a + c log2 n + d log2 N);
//            either never finer than the pixel's footprint
//   lobe     the distance-based correction: the lobe, an angle about r seen from p,
//            covers a patch of the proxy about |x - p| / |x - c| as wide seen from c,
//            so the lookup uses N' = N (|x - c| / |x - p|)^2 (a lobe ~ N^-1/2 wide)
//   diffuse  SH irradiance E(n) of the static environment, as `mirror` has it
//   combined seed 000 eq. 8 with Schlick's F (common/eq8.glsl)
// Where the level lies at or below the pixel's footprint (or 0), the lookup is the
// hardware's own, texture(cube, d): with the proxy at infinity (d parallel to r) and a
// mirror-like N, exactly `mirror`'s.
// Both level scales are the cube's: level L of the Phong chain holds a lobe one texel of
// level L wide, as the box mips' level L has texels as wide as a footprint that picks it.
// The Phong chain's level 0 holds N_0 = (n / 2)^2; a larger N' is at a level below 0, which
// the footprint test below always sends to the hardware's lookup.
// Defines: PROXY (0, 1, 2: parallax/proxy.glsl), DISTANCE_CORRECTION (0/1),
// PHONG_CHAIN (0/1), SH_COEFFICIENTS (9, 25, 49), LIGHTS (0 .. 32).
#if defined VERTEX_SHADER
#include "common/mesh_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/fresnel.glsl"
#include "common/eq8.glsl"
#include "common/sh_irradiance.glsl"
#include "parallax/proxy.glsl"
uniform samplerCube u_environment;  // the probe's cube, box-filtered mips
uniform vec3 u_probe;
uniform float u_exponent;
uniform float u_cube_size;
#if PHONG_CHAIN
uniform samplerCube u_chain;     // its Phong chain, trilinear, face edge u_cube_size
#else
uniform vec3 u_fit;  // a, c, d of the glossiness fit
#endif
out vec4 f_color;

#if PHONG_CHAIN
// The chain level whose lobe is N's (chain_gpu.texel_exponents).
float glossy_level(float exponent) {
    return log2(u_cube_size) - 1.0 - 0.5 * log2(exponent);
}
#else
// b = W(u): the trilinear level whose blur is 2^u texels wide (prefilter/glossiness.py).
float glossy_level(float exponent) {
    float u = u_fit.x + u_fit.y * log2(u_cube_size) + u_fit.z * log2(exponent);
    float k = floor(u);
    return k + (exp2(2.0 * (u - k)) - 1.0) / 3.0;
}
#endif

void main() {
    const float PI = 3.14159265358979;
    vec3 n, r;
    reflection_frame(v_world_normal, v_world_position, u_camera_position, n, r);
    vec3 d = r;
    float exponent = u_exponent;
    float t = proxy_exit(v_world_position, r);
    if (t > 0.0) {
        d = v_world_position + t * r - u_probe;
#if DISTANCE_CORRECTION
        float ratio = clamp(t / max(length(d), 1e-30), 1e-3, 1e3);
        exponent = u_exponent / (ratio * ratio);
#endif
    }
    // Normalised: the hardware's cube LOD comes from the derivatives of the vector it is
    // given, and some (llvmpipe) take them before the projection onto the face, so a
    // vector of varying length (the box's hits) would change the level r would get.
    vec3 dn = normalize(d);
    float level = glossy_level(exponent);
    vec3 sharp = texture(u_environment, dn).rgb;
#if PHONG_CHAIN
    vec3 blurred = textureLod(u_chain, dn, level).rgb;
#else
    vec3 blurred = textureLod(u_environment, dn, level).rgb;
#endif
    // The footprint of a pixel: the angle d turns through per pixel, in face texels of
    // about 2 / n radians (as kautz's lod_mode=level).
    float turn = max(length(dFdx(dn)), length(dFdy(dn)));
    float footprint = log2(max(turn * u_cube_size * 0.5, 1e-6));
    vec3 glossy = level <= max(footprint, 0.0) ? sharp : blurred;
    f_color = vec4(eq8_shade(n, r, sh_irradiance_if(u_kd, n) / PI, glossy, u_kd, u_fresnel), 1.0);
}
#endif
