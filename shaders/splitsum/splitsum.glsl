#version 330 core
// Method `splitsum` (app/envstudio/methods/splitsum/method.py): Karis's split sum for the
// reference's microfacet material (GGX D, height-correlated Smith G2, Schlick F of f0),
//   L_o = k_d (1 - F(n.v)) E(n) / pi + L_pre(r, alpha) (f0 A + B) c,
// L_pre from two levels of the GGX-prefiltered chain (N = V = R, prefilter/lobe_chain.glsl),
// (A, B) = DFG table at (n.v, sqrt(alpha)), c = 1 + f0 (1 / (A + B) - 1) with multiscatter
// (Fdez-Aguera 2019, as Filament), else 1; E(n) from SH plus cap lights.
// With SAMPLED (lobe_samples > 0), L_pre (f0 A + B) is replaced by u_samples importance samples of the true
// view-dependent lobe per pixel: half vectors h ~ D(h) (n.h), l = reflect(-v, h), weight
// F(v.h) G2 (v.h) / ((n.h)(n.v)), each read from the environment's mip level whose texels
// cover 1 / (u_samples pdf(l)) (filtered importance sampling, Krivanek & Colbert 2008).
// Defines: SH_COEFFICIENTS (9, 25, 49), LIGHTS (0 .. 32), SAMPLED (0, 1).
#if defined VERTEX_SHADER
#include "common/mesh_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/fresnel.glsl"
#include "common/eq8.glsl"
#include "common/sh_irradiance.glsl"
#include "common/sampling.glsl"
#include "common/random.glsl"
uniform sampler2D u_dfg;
uniform float u_roughness;
uniform bool u_multiscatter;
#if SAMPLED
uniform samplerCube u_environment;  // with its mip chain, trilinear
uniform int u_samples;
uniform float u_source_max;         // its coarsest mip level
uniform float u_texel_log2;         // log2(2 / n), n its face edge
#else
uniform samplerCube u_level_a;      // level k (k = 0: the environment itself)
uniform samplerCube u_level_b;      // level k + 1
uniform float u_level_mix;          // t: alpha's lod (K - 1) sqrt(alpha) = k + t
#endif
out vec4 f_color;

#if SAMPLED
// (1 / S) sum F G_vis L(l): the specular integral for the view v by importance sampling.
vec3 sampled_specular(vec3 n, vec3 v, float n_dot_v, vec3 f0) {
    mat3 frame = frame_around(n);
    float a2 = u_roughness * u_roughness;
    // one stratified set per pixel: u = (i + 1/2) / S, phi by the golden ratio, both shifted
    vec2 shift = random2(uvec2(gl_FragCoord.xy), 0u, 0u);
    float count = float(u_samples);
    vec3 sum = vec3(0.0);
    for (int i = 0; i < u_samples; ++i) {
        vec2 xi = fract(shift + vec2((float(i) + 0.5) / count, float(i) * 0.6180339887498949));
        float cos_h = sqrt((1.0 - xi.x) / (1.0 + (a2 - 1.0) * xi.x));
        float sin_h = sqrt(max(0.0, 1.0 - cos_h * cos_h));
        float phi = 2.0 * PI * xi.y;
        vec3 h = frame * vec3(sin_h * cos(phi), sin_h * sin(phi), cos_h);
        float v_dot_h = dot(v, h);
        vec3 l = 2.0 * v_dot_h * h - v;
        float n_dot_l = dot(n, l);
        if (n_dot_l <= 0.0 || v_dot_h <= 0.0) continue;
        float g_vis = ggx_g2(n_dot_l, n_dot_v, u_roughness) * v_dot_h / (cos_h * n_dot_v);
        vec3 fresnel = f0 + (1.0 - f0) * pow(1.0 - v_dot_h, 5.0);
        float pdf = ggx_d(cos_h, u_roughness) * cos_h / (4.0 * v_dot_h);
        vec3 m = abs(l);
        float lod = 0.5 * (-log2(count * pdf)) - u_texel_log2
                    - 1.5 * log2(max(m.x, max(m.y, m.z)));
        sum += fresnel * g_vis * textureLod(u_environment, l, clamp(lod, 0.0, u_source_max)).rgb;
    }
    return sum / count;
}
#endif

void main() {
    vec3 n, r;
    reflection_frame(v_world_normal, v_world_position, u_camera_position, n, r);
    vec3 v = normalize(u_camera_position - v_world_position);
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    vec3 f0 = vec3(u_fresnel);
    vec2 dfg = texture(u_dfg, vec2(n_dot_v, sqrt(u_roughness))).rg;
    vec3 compensation = u_multiscatter ? 1.0 + f0 * (1.0 / (dfg.x + dfg.y) - 1.0) : vec3(1.0);
#if SAMPLED
    vec3 specular = sampled_specular(n, v, n_dot_v, f0);
#else
    vec3 radiance = mix(texture(u_level_a, r).rgb, texture(u_level_b, r).rgb, u_level_mix);
    vec3 specular = radiance * (f0 * dfg.x + dfg.y);
#endif
    vec3 diffuse = u_kd * (1.0 - schlick_fresnel(u_fresnel, n_dot_v)) * sh_irradiance_if(u_kd, n) / PI;
    f_color = vec4(diffuse + specular * compensation, 1.0);
}
#endif
