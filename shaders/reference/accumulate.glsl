#version 430 core
// Method `reference`, accumulation pass: each frame adds one batch of
// u_samples multiple-importance-sampled estimates (balance heuristic, Veach
// 1995) of the exitant radiance of seed 000 eq. 1 per reflector pixel, drawn
// by randomised QMC (sample2 below).
//
// k_d and f_lambda are linear RGB (material.glsl): F, and each sample's weight, per channel;
// the directions drawn do not depend on them.
// Model 0 (seed 000 eq. 8): L_o = (1 - F) k_d D + F P with Schlick F(n.v)
//   D = 1/pi  int L(l) max(n.l, 0) dl         (eq. 3-4: cosine lobe + environment sampling)
//   P = (N+1)/2pi int L(l) max(r.l, 0)^N dl   (eq. 7: Phong lobe + environment sampling)
// The Phong lobe is integrated over the hemisphere about r, as eq. 7's
// reparameterised (prefiltered) map does, not clipped by the surface.
// Model 1 (microfacet): k_d/pi (1 - F(n.v)) + GGX D G2 F(v.h) / (4 n.l n.v),
//   alpha = sqrt(2 / (4N + 2)) (a Phong exponent N is about a Blinn exponent 4N).
// Model 2 (banks, seed 004 section 5.3): L_o = (1 - F) k_d D + F B with Schlick F(n.v),
//   B = c int f_banks(v, l; t) L(l) [max(n.l, 0)] dl, the bracket only with
//   u_self_shadowing (without it the whole sphere, as method `banks`' 3D map);
//   c = 1 / int f_banks dl with u_banks_normalize (method banks' `normalize`), else 1.
//
// A batch may be drawn in chunks (u_chunk_first, u_chunk_samples): llvmpipe
// ends an invocation's loops after 65 535 iterations in all, so there a pixel
// draws at most SOFTWARE_SAMPLES_PER_BATCH (methods/sample_allocation.py) per
// draw. Output (additive blending into the batch target): sum of the chunk's
// estimates (rgb) and their count (a); merge_batch.glsl turns the batch into
// its mean and adds it, and its square, to the accumulation.
// With UNTRACED_TOO (and TRACE_LOCAL) a second output holds the untraced estimate
// of the same samples: each direction's weight times the environment along it,
// the lobe left whole (the environment-map model; compare's approximation error).
#if defined VERTEX_SHADER
#include "common/mesh_world.glsl"
#include "common/mesh_tangent.glsl"
uniform mat4 u_view;
uniform mat4 u_projection;

void main() {
    gl_Position = u_projection * u_view * mesh_world();
    mesh_tangent();
}
#elif defined FRAGMENT_SHADER
#include "common/random.glsl"
#include "common/sobol.glsl"
#include "common/fresnel.glsl"
#include "common/sampling.glsl"
#include "reference/material.glsl"
#include "reference/radiance.glsl"
#include "common/banks_brdf.glsl"

uniform vec3 u_camera_position;
uniform int u_samples;
uniform int u_frame;

uniform int u_sequence;
uniform int u_environment_sampling;  // 0: the whole map; 1: inside the glossy lobe's cap

const float LOBE_CAP_FLOOR = 1e-3;
const float GGX_CAP_TAIL = 1e-3;

// Number of this batch's first sample in the pixel's sequence (set by main).
uint g_first_sample;

// Two numbers in [0, 1) for sample i of this batch and one technique.
// Sequence 0: independent batches, R2-stratified within each (the spread of
// batch means is an honest standard error). Sequence 1: one Owen-scrambled
// Sobol sequence per pixel continued across batches (errors fall faster; the
// spread of batch means then overstates them).
vec2 sample2(uvec2 pixel, uint technique, uint i) {
    if (u_sequence == 1) return sobol2(pixel, technique, g_first_sample + i);
    return stratified2(pixel, uint(u_frame), technique, i);
}

// Sample i's pixel-footprint offset, glossy-lobe sample (Phong or GGX) and
// environment sample for the glossy term, drawn jointly from one 6D sequence
// under `sobol`: a bright light whose reflection crosses the footprint is then
// stratified in all three at once.
vec2 g_footprint;
vec2 g_lobe;
vec2 g_environment;

void draw_joint(uvec2 pixel, uint i) {
    if (u_sequence == 1) {
        sobol6(pixel, g_first_sample + i, g_footprint, g_lobe, g_environment);
    } else {
        g_footprint = stratified2(pixel, uint(u_frame), 6u, i);
        g_lobe = stratified2(pixel, uint(u_frame), 2u, i);
        g_environment = stratified2(pixel, uint(u_frame), 3u, i);
    }
}

in vec3 v_world_position;
in vec3 v_world_normal;
in vec3 v_world_tangent;
layout(location = 0) out vec4 f_batch;
#if UNTRACED_TOO
layout(location = 1) out vec4 f_untraced;
#endif
// The untraced estimate of the samples so far (UNTRACED_TOO): the same weights.
vec3 g_untraced = vec3(0.0);

// Radiance along l as traced, and its weighted environment radiance added to g_untraced.
vec3 incident_weighted(vec3 p, vec3 n, vec3 l, vec3 weight) {
#if UNTRACED_TOO
    g_untraced += weight * environment_radiance(l);
#endif
    return weight * incident(p, n, l);
}

// One MIS sample pair for D (cosine lobe) and P (Phong lobe): four directions
// with their weights, then one loop that traces them (a single call site of
// incident(), so the traversal is compiled once).
// The MIS pair for D (seed 000 eq. 3-4) of models 0 and 2: directions[0..1], weights[0..1].
void sample_diffuse(vec3 n, uvec2 pixel, uint index, vec3 diffuse_weight,
                    inout vec3 directions[4], inout vec3 weights[4]) {
    // cosine-lobe sample for D (pdf = f)
    directions[0] = sample_cosine(n, sample2(pixel, 0u, index));
    float pdf = max(dot(n, directions[0]), 0.0) / PI;
    weights[0] = pdf > 0.0 ? diffuse_weight * balance(pdf, env_pdf(directions[0])) : vec3(0.0);
    // environment sample for D
    directions[1] = sample_environment(sample2(pixel, 1u, index));
    pdf = env_pdf(directions[1]);
    float f = max(dot(n, directions[1]), 0.0) / PI;
    weights[1] = f > 0.0 ? diffuse_weight * balance(pdf, f) * f / pdf : vec3(0.0);
}

vec3 sample_eq8(vec3 p, vec3 n, vec3 v, vec3 r, uvec2 pixel, uint index) {
    float N = u_phong_exponent;
    vec3 F = schlick_fresnel(u_fresnel, dot(n, v));
    vec3 diffuse_weight = (1.0 - F) * u_kd;
    vec3 directions[4];
    vec3 weights[4];
    sample_diffuse(n, pixel, index, diffuse_weight, directions, weights);
    float pdf;
    float f;
    // Phong-lobe sample for P (pdf = lobe; its weight below)
    directions[2] = sample_phong(r, N, g_lobe);
    // environment sample for P: from the part of the map inside the lobe's cap
    // (where the lobe is above LOBE_CAP_FLOOR of its peak) when it fits the
    // tables' CONE_MAX_ROWS, else from the whole map; either is paired with the
    // lobe sample by the balance heuristic, so the lobe outside the cap stays covered.
    bool cone = u_environment_sampling == 1 && setup_cone(r, pow(LOBE_CAP_FLOOR, 1.0 / N));
    directions[3] = cone ? sample_cone(g_environment) : sample_environment(g_environment);
    pdf = cone ? cone_pdf(directions[3]) : env_pdf(directions[3]);
    f = phong_lobe(r, directions[3], N);
    weights[3] = f > 0.0 && pdf > 0.0 ? F * balance(pdf, f) * f / pdf : vec3(0.0);
    float lobe_pdf = phong_lobe(r, directions[2], N);
    float other = cone ? cone_pdf(directions[2]) : env_pdf(directions[2]);
    weights[2] = lobe_pdf > 0.0 ? F * balance(lobe_pdf, other) : vec3(0.0);
    vec3 total = vec3(0.0);
    for (int k = 0; k < 4; ++k) {
        if (any(greaterThan(weights[k], vec3(0.0)))) {
            total += incident_weighted(p, n, directions[k], weights[k]);
        }
    }
    return total;
}

// One MIS sample pair for the microfacet BRDF times the cosine.
vec3 sample_microfacet(vec3 p, vec3 n, vec3 v, uvec2 pixel, uint index) {
    float alpha = microfacet_alpha();
    float n_dot_v = max(dot(n, v), 1e-4);
    vec3 F_view = schlick_fresnel(u_fresnel, n_dot_v);
    // Without a diffuse term, environment samples come from the cap about the
    // mirror direction holding all but GGX_CAP_TAIL of the half vectors' D(h)(n.h)
    // (P(tan^2 theta_h > X) = alpha^2 / (alpha^2 + X): tan(theta_h) = alpha
    // sqrt(1 / tail - 1), theta_l ~ 2 theta_h); the GGX samples cover the rest. Not
    // LOBE_CAP_FLOOR of D's peak: GGX's tails fall as theta^-4, that cap left them 3.2 %
    // of the lobe, and studio.exr's lamps there, drawn by GGX samples alone, were missed
    // by most pixels (alpha = 0.05, 512 spp: median 24 % low; issue 30).
    float cap = min(2.0 * atan(alpha * sqrt(1.0 / GGX_CAP_TAIL - 1.0)), 0.5 * PI);
    bool cone = u_environment_sampling == 1 && all(equal(u_kd, vec3(0.0)))
                && setup_cone(reflect(-v, n), cos(cap));
    vec3 result = vec3(0.0);
    for (int technique = 0; technique < 2; ++technique) {
        vec2 xi = technique == 0 ? g_lobe : g_environment;
        vec3 l;
        if (technique == 0) {
            vec3 h = sample_ggx_half(n, alpha, xi);
            l = reflect(-v, h);
        } else {
            l = cone ? sample_cone(xi) : sample_environment(xi);
        }
        float n_dot_l = dot(n, l);
        if (n_dot_l <= 0.0) continue;
        vec3 h = normalize(l + v);
        float n_dot_h = max(dot(n, h), 0.0);
        float v_dot_h = max(dot(v, h), 1e-4);
        float D = ggx_d(n_dot_h, alpha);
        float pdf_brdf = D * n_dot_h / (4.0 * v_dot_h);
        float pdf_env = cone ? cone_pdf(l) : env_pdf(l);
        vec3 specular = D * ggx_g2(n_dot_l, n_dot_v, alpha) * schlick_fresnel(u_fresnel, v_dot_h)
                        / (4.0 * n_dot_l * n_dot_v);
        vec3 diffuse = u_kd / PI * (1.0 - F_view);
        vec3 f = (specular + diffuse) * n_dot_l;
        float pdf = technique == 0 ? pdf_brdf : pdf_env;
        float other = technique == 0 ? pdf_env : pdf_brdf;
        // Balance weights sum to 1 wherever either pdf is positive: with a diffuse term
        // the environment pdf is positive everywhere, so the diffuse part stays unbiased
        // though the GGX technique ignores it; without one, the GGX pdf covers the lobe.
        if (pdf > 0.0) result += incident_weighted(p, n, l, balance(pdf, other) * f / pdf);
    }
    return result;
}

uniform bool u_banks_normalize;
uniform bool u_self_shadowing;

// Density in solid angle of the Banks lobe's sampling: theta = angle(l, t) uniform
// over the lobe's band [theta0, theta1], phi uniform about t.
float banks_band_pdf(vec3 t, vec3 l, float theta0, float theta1) {
    float c = clamp(dot(l, t), -1.0, 1.0);
    float theta = acos(c);
    if (theta < theta0 || theta > theta1) return 0.0;
    return 1.0 / (2.0 * PI * max(sqrt(1.0 - c * c), 1e-7) * max(theta1 - theta0, 1e-7));
}

// One MIS sample pair for D (cosine lobe) and B (Banks lobe about the tangent t):
// the Banks lobe's band sample (banks_band_pdf) and an environment sample (the
// whole map), by the balance heuristic. Without self-shadowing the Banks
// directions see the environment from any side of the surface (method banks'
// map: "an object using this environment map does reflect light from behind it").
vec3 sample_banks(vec3 p, vec3 n, vec3 t, vec3 v, uvec2 pixel, uint index) {
    vec3 F = schlick_fresnel(u_fresnel, dot(n, v));
    vec3 directions[4];
    vec3 weights[4];
    sample_diffuse(n, pixel, index, (1.0 - F) * u_kd, directions, weights);
    float b = dot(v, t);
    float theta0, theta1, psi;
    banks_band(b, theta0, theta1, psi);
    vec3 scale = F / (u_banks_normalize ? banks_integral(b) : 1.0);
    vec3 e1 = normalize(abs(t.x) < 0.9 ? cross(t, vec3(1.0, 0.0, 0.0)) : cross(t, vec3(0.0, 1.0, 0.0)));
    vec3 e2 = cross(t, e1);
    float theta = mix(theta0, theta1, g_lobe.x);
    float phi = 2.0 * PI * g_lobe.y;
    directions[2] = cos(theta) * t + sin(theta) * (cos(phi) * e1 + sin(phi) * e2);
    directions[3] = sample_environment(g_environment);
    for (int k = 2; k < 4; ++k) {
        vec3 l = directions[k];
        float shadow = u_self_shadowing ? max(dot(n, l), 0.0) : 1.0;
        float f = banks_lobe(dot(l, t), b) * shadow;
        float lobe_pdf = banks_band_pdf(t, l, theta0, theta1);
        float env = env_pdf(l);
        float pdf = k == 2 ? lobe_pdf : env;
        weights[k] = f > 0.0 && pdf > 0.0
                     ? scale * f / pdf * balance(pdf, k == 2 ? env : lobe_pdf) : vec3(0.0);
    }
    vec3 total = vec3(0.0);
    for (int k = 0; k < 4; ++k) {
        if (all(lessThanEqual(weights[k], vec3(0.0)))) continue;
        vec3 l = directions[k];
        bool unshadowed = k >= 2 && !u_self_shadowing;
        if (unshadowed) {
            total += weights[k] * environment_radiance(l);
#if UNTRACED_TOO
            g_untraced += weights[k] * environment_radiance(l);
#endif
        } else {
            total += incident_weighted(p, n, l, weights[k]);
        }
    }
    return total;
}

uniform bool u_pixel_filter;
// Adaptive sampling (methods/reference.py): per pixel, (samples-per-frame units
// drawn before the allocation was set, multiplier m) and the batches since.
uniform bool u_adaptive;
uniform sampler2D u_allocation;
uniform int u_batches_since_allocation;
// This draw's part of the batch: samples [u_chunk_first, u_chunk_first + u_chunk_samples).
uniform int u_chunk_first;
uniform int u_chunk_samples;

void main() {
    // the face normal at the pixel centre, oriented by the triangle's winding as
    // hit_face_normal() is (derivatives before any divergent control flow)
    vec3 centre_face = cross(dFdx(v_world_position), dFdy(v_world_position));
    if (!gl_FrontFacing) centre_face = -centre_face;
    uvec2 pixel = uvec2(gl_FragCoord.xy);
    vec3 batch = vec3(0.0);
    int multiplier = 1;
    g_first_sample = uint(u_frame) * uint(u_samples);
    if (u_adaptive) {
        // this pixel's own count, so its Sobol sequence runs on without gaps
        vec2 allocation = texelFetch(u_allocation, ivec2(pixel), 0).rg;
        multiplier = int(allocation.y);
        g_first_sample = uint(allocation.x + float(u_batches_since_allocation) * allocation.y)
                         * uint(u_samples);
    }
    int count = u_samples * multiplier;
    int last = min(count, u_chunk_first + u_chunk_samples);
    if (last <= u_chunk_first) discard;  // this pixel's batch ended in an earlier chunk
    g_path_pixel = pixel;
    int taken = 0;
    for (int i = u_chunk_first; i < last; ++i) {
        // With the pixel filter each sample sees another point of the pixel's
        // footprint (box filter, stratified), the surface there found by a
        // camera ray (footprint.glsl): the anti-aliased image that mip-mapped
        // lookups approximate. Without it, the pixel centre only.
        draw_joint(pixel, uint(i));
        vec3 p = v_world_position;
        vec3 n = normalize(v_world_normal);
        vec3 g = centre_face;
        if (u_pixel_filter && !footprint_surface(gl_FragCoord.xy + g_footprint - 0.5,
                                                 u_camera_position, p, n, g)) {
            continue;
        }
        ++taken;
        vec3 v = normalize(u_camera_position - p);
        // Two-sided: the side of the face the camera sees. A shading normal
        // still turned away from the viewer (silhouettes of smooth-shaded
        // meshes) reflects nothing, as in a path tracer's shading frame.
        if (dot(g, v) < 0.0) {
            n = -n;
            g = -g;
        }
        if (dot(n, v) <= 0.0) continue;
        g_path_face = normalize(g);
        g_path_sample = g_first_sample + uint(i);
        g_path_stream = 0u;
        vec3 r = reflect(-v, n);
        if (u_brdf_model == 0) {
            batch += sample_eq8(p, n, v, r, pixel, uint(i));
        } else if (u_brdf_model == 1) {
            batch += sample_microfacet(p, n, v, pixel, uint(i));
        } else {
            batch += sample_banks(p, n, banks_tangent(v_world_tangent, n), v, pixel, uint(i));
        }
    }
    // count the footprint points on the reflectors only: the mean over the covered footprint
    f_batch = vec4(batch, float(taken));
#if UNTRACED_TOO
    f_untraced = vec4(g_untraced, float(taken));
#endif
}
#endif
