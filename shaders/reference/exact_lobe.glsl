#version 430 core
// The exact untraced reference's glossy term for the models whose lobe depends on (n, v) or
// (v, t) together (measure/exact_lobes.py): microfacet (GGX D, height-correlated Smith G2,
// Schlick F(v.h), over 4 n.v; material.glsl model 1) and banks (seed 004 section 5.3,
// banks_brdf.glsl; accumulate.glsl model 2). One invocation a footprint sample adds
//     sum over nodes of  f(n, v, l_node) W_node
// to its sum: a descent of the environment's mip pyramid (seed 004 section 5.1, Figure 2;
// prefilter/hierarchical.py builds it), from each node of the start level down. A node
// (radiance sum W = sum L dw, mean direction d, cap radius rho about d, radiance centroid s,
// second moment S) is skipped when the lobe is zero over its cap, accepted with the lobe's
// mean over its radiance (lobe_mean) when the lobe is smooth over it (classify), and
// refined into its four children otherwise. A texel that is still refined is cut into k x k parts of its own
// radiance, each taken at its centre (finer than the lobe at its distance).
// A microfacet lobe narrower than a texel's finest part has its peak taken over half vectors
// instead (peak_cell, PEAK_PASS).
//
// Chunks: u_first_sample.. of the sample buffers; llvmpipe ends an invocation's loops after
// 65 535 iterations, so a dispatch spends at most u_budget on a sample and keeps its stack
// for the next one (Python dispatches until every stack is empty).
#if defined COMPUTE_SHADER
layout(local_size_x = 64) in;
#include "common/fresnel.glsl"
#include "common/latlong.glsl"
#include "common/banks_brdf.glsl"

layout(std430, binding = 0) readonly buffer Normals { vec4 normals[]; };
layout(std430, binding = 1) readonly buffer Views { vec4 views[]; };
layout(std430, binding = 2) readonly buffer Tangents { vec4 tangents[]; };
layout(std430, binding = 3) buffer Sums { vec4 sums[]; };
// Each sample's descent, in the buffer (and so kept between dispatches): its stack of nodes
// (column, row, level) and how many it holds (-1: not started; 0: finished).
layout(std430, binding = 4) buffer Stacks { ivec4 stacks[]; };
layout(std430, binding = 5) buffer Tops { int tops[]; };
// Level 0's rows, then its columns (exact_lobes.band_table): a row's (cos, sin) of its upper
// edge theta0 and its texels' solid angle; a column's (cos, sin) of its left edge phi0.
layout(std430, binding = 6) readonly buffer Bands { vec4 bands[]; };

// The pyramid (exact_lobes.PyramidTextures), per level:
uniform sampler2D u_radiance;   // W (rgb, radiance x sr), rho (a, radians)
uniform sampler2D u_direction;  // d (xyz, unit), the acceptance's shrink for a bright node (a)
uniform sampler2D u_point0;     // the three points of the node's rule (xyz each; lobe_mean)
uniform sampler2D u_point1;
uniform sampler2D u_point2;
uniform ivec2 u_level0;         // (columns, rows) of level 0
uniform int u_start_level;
uniform int u_budget;           // iterations a dispatch may spend on a sample
uniform int u_first_sample;
uniform int u_samples;
uniform float u_accept;
uniform float u_alpha;
uniform vec3 u_fresnel;
uniform bool u_banks_normalize;
uniform bool u_self_shadowing;

const float PI = 3.14159265358979;
const int MAX_SPLIT = 16;
// Banks' acceptance inside its band and across its edges, in units of u_accept times the
// band's half width: against the brute force (sunrise, s = 0.5 and 0.9, with and without
// self-shadowing) inside 3 read a median of 0.53 %, 1.5 under 0.17 %; an edge at 0.3 took 7
// times as long as at 1 for the same error.
const float BANKS_INSIDE = 1.5;
// GGX's acceptance away from its peak, in units of the node's distance to it: the tail
// falls as a power of that distance, smooth at its own scale (measured against the brute
// force: 2 reads 2.6 times fewer nodes than 1 at a mean within 0.03 %; 3 errs by 3-5 % at
// single samples).
const float GGX_TAIL = 2.0;
const float BANKS_EDGE = 1.0;
// GGX across the horizon <n, l> = 0, where the lobe has a kink: just above it the lobe rises
// as k <n, l> with k = D F / (4 <n, v>) dG2/d<n, l> = D F / (2 alpha <n, v>) (G2 ~ 2 <n, l> /
// alpha there), and the three-point rule over a node of radius rho across it errs by about
// k rho^3 of its radiance: nodes there are refined to rho^2 k under this.
// k grows with the node's brightness over the map's mean, as the shrink's scale. Against
// tests/microfacet_numpy_reference.py on a sphere under a small sun (32 x 64 map, 584 pixel
// centres): without it up to 23 % at alpha = 0.5 (at the pixels whose horizon crosses the
// sun), with 3e-4 at most 1.2 % at every alpha (1.1 % with 1e-4; 0.08 % with the shrink too);
// on the sunrise sphere at 96 x 96 x 16 samples it costs 1.6 times the time at N = 10, 1.1 at 1000.
const float HORIZON_TOLERANCE = 3e-4;
const int STACK = STACK_SIZE;
// A GGX lobe narrower across than a texel's finest part (a grazing view of a sharp lobe: the
// reflected lobe is about 2 alpha <n, v> wide across the plane of incidence, and the
// three-point rule over a part wider than it errs by 12-50 %) is taken in two: the half
// vectors within a cap about n by a midpoint rule over GGX's own distribution (PEAK_CELLS x
// PEAK_CELLS cells of equal D <n, h>, each reading the texel its reflected direction falls in;
// the PEAK_PASS variant of main), the rest by the descent with the cap cut out of its lobe.
// The cap's angle is where the descent's finest parts resolve the lobe again (a part's
// h-space size under u_accept GGX_TAIL times its distance to n), at least PEAK_MIN_ALPHAS
// alpha. Against the albedo on a 32-row map at alpha = 0.01: 0.02 % and 0.12 % at
// <n, v> = 0.1 and 0.05 (12 % and 47 % without); against a NumPy sum over half vectors on a
// varying map 0.07 % (tests/test_exact_microfacet.py). On the sunrise sphere at N = 1000 it
// takes 5 of 72 989 samples (the most grazing) and no time.
const int PEAK_CELLS = 64;
const float PEAK_MIN_ALPHAS = 4.0;
const float PEAK_MAX = 0.5;  // radians

// Sample frame, set once per invocation.
vec3 g_n;
vec3 g_v;
vec3 g_t;
float g_n_dot_v;
float g_band_lo;    // banks: the band of angle(l, t) where the lobe is nonzero
float g_band_hi;
float g_band_half;
vec3 g_banks_scale;
float g_peak_cap;     // microfacet: the cap of half vectors taken by peak_cell (0: none)
float g_cos_peak_cap; // its cosine (above 1: none)

float ggx_d(float n_dot_h, float alpha) {
    float a2 = alpha * alpha;
    float d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

float ggx_g2(float n_dot_l, float n_dot_v, float alpha) {
    float a2 = alpha * alpha;
    float gl = n_dot_v * sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2);
    float gv = n_dot_l * sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2);
    return 2.0 * n_dot_l * n_dot_v / max(gl + gv, 1e-9);
}

float angle_between(vec3 a, vec3 b) { return atan(length(cross(a, b)), dot(a, b)); }

// The lobe (BRDF times the cosine where the model has one), per channel, at unit l.
vec3 lobe(vec3 l) {
    if (MODEL == 1) {
        float n_dot_l = dot(g_n, l);
        if (n_dot_l <= 0.0) return vec3(0.0);
        vec3 h = normalize(l + g_v);
        if (dot(g_n, h) > g_cos_peak_cap) return vec3(0.0);  // peak_cell's
        float d = ggx_d(max(dot(g_n, h), 0.0), u_alpha);
        float g2 = ggx_g2(n_dot_l, g_n_dot_v, u_alpha);
        return d * g2 * schlick_fresnel(u_fresnel, max(dot(g_v, h), 0.0)) / (4.0 * g_n_dot_v);
    }
    float shadow = u_self_shadowing ? max(dot(g_n, l), 0.0) : 1.0;
    return g_banks_scale * banks_lobe(dot(l, g_t), dot(g_v, g_t)) * shadow;
}

// 0: the lobe is zero over the cap (d, rho); 1: smooth over it, take it at the centroid;
// 2: refine. `shrink`: the node's brightness over the map's mean, at least 1, to the power
// exact_lobes.BRIGHT_POWER; `split`: parts a texel edge is cut into when it is refined at
// level 0.
int classify(vec3 d, float rho, float shrink, out int split) {
    float from_n = angle_between(g_n, d);
    bool shadowed = MODEL == 1 || u_self_shadowing;
    split = 4;
    if (shadowed && from_n - rho >= 0.5 * PI) return 0;
    if (MODEL == 1) {
        vec3 h = normalize(d + g_v);
        float rho_h = rho / (2.0 * max(dot(g_v, h), 1e-3));
        float from_h = angle_between(g_n, h);
        if (from_h + rho_h < g_peak_cap) return 0;  // peak_cell's
        float scale = u_accept * max(u_alpha, GGX_TAIL * (from_h - rho_h)) / shrink;
        split = int(clamp(ceil(rho_h / scale), 2.0, float(MAX_SPLIT)));
        bool accepted = rho_h <= scale;
        if (from_n + rho > 0.5 * PI) {  // across the horizon
            float k = ggx_d(cos(max(from_h - rho_h, 0.0)), u_alpha) / (2.0 * u_alpha * g_n_dot_v)
                      * (shrink * shrink * shrink);
            float widest = sqrt(HORIZON_TOLERANCE / max(k, 1e-20));
            split = int(clamp(max(float(split), ceil(rho / widest)), 2.0, float(MAX_SPLIT)));
            accepted = accepted && rho <= widest;
        }
        return accepted ? 1 : 2;
    }
    // banks: inside the band the lobe is cos(angle(l, t) - psi) - s, which the three-point
    // rule takes exactly to third order, so nodes of a fraction of the band's width pass; its
    // edges (and the horizon, with self-shadowing) are kinks, taken with finer nodes
    float from_t = angle_between(g_t, d);
    if (from_t + rho <= g_band_lo || from_t - rho >= g_band_hi) return 0;
    bool inside = from_t - rho >= g_band_lo && from_t + rho <= g_band_hi;
    bool horizon = u_self_shadowing && from_n + rho > 0.5 * PI;
    float scale = (inside && !horizon ? BANKS_INSIDE : BANKS_EDGE) * u_accept * g_band_half
                  / shrink;
    split = int(clamp(ceil(rho / scale), 2.0, float(MAX_SPLIT)));
    return rho <= scale ? 1 : 2;
}

// The lobe's mean over three points (mat3 columns).
vec3 lobe_mean(mat3 points) {
    return (lobe(points[0]) + lobe(points[1]) + lobe(points[2])) / 3.0;
}

// The three points of a node of level >= 1 accepted as smooth: its three-point rule over the
// node's radiance, exact for quadratics (exact_lobes.node_points).
mat3 node_points(ivec3 node) {
    return mat3(texelFetch(u_point0, node.xy, node.z).xyz, texelFetch(u_point1, node.xy, node.z).xyz,
                texelFetch(u_point2, node.xy, node.z).xyz);
}

// (cos x, sin x) of a small angle, |x| at most a texel's edge (pi / 4 and less: within 3e-8),
// by their Taylor series: the parts' angles are a table's plus such offsets, without the
// trigonometric functions every iteration of the descent would pay for (llvmpipe runs each
// branch of the loop for all 8 invocations it takes together).
vec2 cos_sin_small(float x) {
    float x2 = x * x;
    float c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
    float s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0))));
    return vec2(c, s);
}

// (cos, sin) of a + x from (cos a, sin a) and a small x.
vec2 turned(vec2 a, float x) {
    vec2 b = cos_sin_small(x);
    return vec2(a.x * b.x - a.y * b.y, a.y * b.x + a.x * b.y);
}

// Part k of texel (column, row) of level 0, cut into split x split parts (split 1: the whole
// texel), its radiance constant over it. The part's centroid and second moment are its
// area's: theta's mean weighted by sin(theta), m + cot(m) (1 - q cot q) for the part's middle
// m and half height q (1 - q cot q = q^2 / 3 + q^4 / 45 + 2 q^6 / 945 + ...), and the variances
// (2 q)^2 / 12 along theta, (sin(theta) dphi)^2 / 12 along phi; its solid angle
// 2 dphi sin(m) sin(q). The three points of the rule over that distribution (node_points'),
// its second moment diagonal in (along phi, along theta); `weight`: the part's radiance
// times its solid angle.
mat3 part_points(ivec2 texel, int split, int k, out vec3 weight) {
    vec4 row = bands[texel.y];
    vec2 column = bands[u_level0.y + texel.x].xy;
    float height = PI / float(u_level0.y * split);
    float dphi = 2.0 * PI / float(u_level0.x * split);
    float q = 0.5 * height;
    vec2 middle = turned(row.xy, (float(k / split) + 0.5) * height);
    float q2 = q * q;
    float shift = middle.x / middle.y * q2 * (1.0 / 3.0 + q2 * (1.0 / 45.0 + q2 * (2.0 / 945.0)));
    vec2 theta = turned(middle, shift);
    vec2 phi = turned(column, (float(k % split) + 0.5) * dphi);
    float omega = 2.0 * dphi * middle.y * cos_sin_small(q).y;
    vec3 d = vec3(theta.y * phi.y, theta.x, -theta.y * phi.x);
    vec3 along_theta = vec3(theta.x * phi.y, -theta.y, -theta.x * phi.x);
    vec3 along_phi = vec3(phi.x, 0.0, phi.y);
    // sqrt(2) times the standard deviations sin(theta) dphi / sqrt(12) and height / sqrt(12)
    vec3 c1 = (0.40824829 * theta.y * dphi) * along_phi;
    vec3 c2 = (0.40824829 * height) * along_theta;
    weight = texelFetch(u_radiance, texel, 0).rgb / row.z * omega;
    return mat3(normalize(d + c1), normalize(d - 0.5 * c1 + 0.8660254 * c2),
                normalize(d - 0.5 * c1 - 0.8660254 * c2));
}

// Cell k of the peak cap: half vectors of equal probability under D <n, h> (u = F(theta), the
// cap's share u_cap of it, midpoints in u and phi), each l = reflect(-v, h) read at its texel:
// L(l) G2 F <v, h> / (<n, v> <n, h>) times the cell's probability (the lobe times dl = 4 <v, h>
// dh, over D <n, h> dh).
vec3 peak_cell(int k) {
    float a2 = u_alpha * u_alpha;
    float t_cap = tan(g_peak_cap);
    float u_cap = t_cap * t_cap / (a2 + t_cap * t_cap);
    float u = u_cap * (float(k / PEAK_CELLS) + 0.5) / float(PEAK_CELLS);
    float phi = 2.0 * PI * (float(k % PEAK_CELLS) + 0.5) / float(PEAK_CELLS);
    float cos_t = sqrt((1.0 - u) / (1.0 + (a2 - 1.0) * u));
    float sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    vec3 e1 = normalize(abs(g_n.y) < 0.9 ? cross(g_n, vec3(0.0, 1.0, 0.0)) : cross(g_n, vec3(1.0, 0.0, 0.0)));
    vec3 e2 = cross(g_n, e1);
    vec3 h = sin_t * (cos(phi) * e1 + sin(phi) * e2) + cos_t * g_n;
    float v_dot_h = dot(g_v, h);
    vec3 l = 2.0 * v_dot_h * h - g_v;
    float n_dot_l = dot(g_n, l);
    if (v_dot_h <= 0.0 || n_dot_l <= 0.0) return vec3(0.0);
    ivec2 texel = min(ivec2(latlong_uv(l) * vec2(u_level0)), u_level0 - 1);
    vec3 radiance = texelFetch(u_radiance, texel, 0).rgb / latlong_texel_solid_angle(texel, u_level0);
    float g2 = ggx_g2(n_dot_l, g_n_dot_v, u_alpha);
    vec3 f = schlick_fresnel(u_fresnel, v_dot_h);
    return radiance * f * (g2 * v_dot_h / (g_n_dot_v * cos_t) * u_cap / float(PEAK_CELLS * PEAK_CELLS));
}

// A stack entry is a node (column, row, level >= 0) or part k of a texel cut into split x split
// parts (column, row, -1 - (32 k + split)): one loop, one node or part an iteration, so that
// the loop's count in llvmpipe (which runs 8 samples as one) is the largest sample's, never
// the sum of nested loops over the samples that take them.
const int PART_CODE = 32;

// The frame of sample `sample_index` (g_*); false where it faces away (nothing reflected).
bool set_frame(int sample_index) {
    g_n = normals[sample_index].xyz;
    g_v = views[sample_index].xyz;
    g_n_dot_v = dot(g_n, g_v);
    if (g_n_dot_v <= 0.0) return false;
    g_peak_cap = 0.0;
    g_cos_peak_cap = 2.0;
    if (MODEL == 1) {
        float part = 0.7 * PI / float(u_level0.y * MAX_SPLIT);  // a finest part's cap radius
        if (2.0 * u_alpha * g_n_dot_v < part) {
            float resolved = part / (2.0 * u_accept * GGX_TAIL * g_n_dot_v);
            g_peak_cap = min(max(PEAK_MIN_ALPHAS * u_alpha, resolved), PEAK_MAX);
            g_cos_peak_cap = cos(g_peak_cap);
        }
    }
    if (MODEL == 2) {
        g_t = tangents[sample_index].xyz;
        float b = dot(g_v, g_t);
        float psi;
        banks_band(b, g_band_lo, g_band_hi, psi);
        g_band_half = acos(u_sharpness);
        g_banks_scale = schlick_fresnel(u_fresnel, g_n_dot_v)
                        / (u_banks_normalize ? banks_integral(b) : 1.0);
    }
    return true;
}

#if defined PEAK_PASS
// The peak caps' cells, one pass after the descent (a separate loop keeps the descent's lean).
void main() {
    int index = int(gl_GlobalInvocationID.x);
    if (index >= u_samples) return;
    int sample_index = u_first_sample + index;
    if (!set_frame(sample_index) || g_peak_cap <= 0.0) return;
    vec3 total = vec3(0.0);
    for (int row = 0; row < PEAK_CELLS; ++row) {  // two loops of 64: llvmpipe's loop limit
        for (int column = 0; column < PEAK_CELLS; ++column) total += peak_cell(row * PEAK_CELLS + column);
    }
    sums[sample_index] += vec4(total, 0.0);
}
#else
void main() {
    int index = int(gl_GlobalInvocationID.x);
    if (index >= u_samples) return;
    int sample_index = u_first_sample + index;
    int top = tops[index];
    if (top == 0) return;  // finished in an earlier dispatch
    if (!set_frame(sample_index)) {
        tops[index] = 0;
        return;
    }
    // the sample's stack, kept in the buffer between dispatches
    int base = index * STACK;
    if (top < 0) {  // the first dispatch: every node of the start level
        ivec2 start = textureSize(u_radiance, u_start_level);
        top = start.x * start.y;
        for (int k = 0; k < top; ++k) stacks[base + k] = ivec4(k % start.x, k / start.x, u_start_level, 0);
    }
    vec3 total = vec3(0.0);
    int budget = u_budget;
    while (top > 0 && budget > 0) {
        ivec3 node = stacks[base + --top].xyz;
        --budget;
        // What the iteration integrates, if anything: part k of a texel cut into split x split
        // parts (split 1: a whole texel accepted at level 0) over its area, or a node of level
        // >= 1 over its radiance. One lobe_mean call takes either: llvmpipe runs every branch
        // any of the 8 invocations it runs as one takes, so each call site (and each
        // trigonometric function) costs every iteration.
        int split = 0;  // 0: no part
        int k = 0;
        bool whole_node = false;  // a node of level >= 1, by its own three points
        vec4 w = vec4(0.0);
        if (node.z < 0) {
            int code = -1 - node.z;
            split = code % PART_CODE;
            k = code / PART_CODE;
            if (k + 1 < split * split) {
                stacks[base + top++] = ivec4(node.xy, -1 - ((k + 1) * PART_CODE + split), 0);
            }
        } else {
            w = texelFetch(u_radiance, node.xy, node.z);
            if (w.r + w.g + w.b <= 0.0) continue;
            int parts;
            vec4 direction = texelFetch(u_direction, node.xy, node.z);
            int verdict = classify(direction.xyz, w.a, direction.a, parts);
            if (verdict == 0) continue;
            if (verdict == 1) {
                whole_node = node.z > 0;
                split = whole_node ? 0 : 1;
            } else if (node.z == 0) {
                stacks[base + top++] = ivec4(node.xy, -1 - parts, 0);
            } else {
                ivec2 child = 2 * node.xy;
                stacks[base + top++] = ivec4(child, node.z - 1, 0);
                stacks[base + top++] = ivec4(child + ivec2(1, 0), node.z - 1, 0);
                stacks[base + top++] = ivec4(child + ivec2(0, 1), node.z - 1, 0);
                stacks[base + top++] = ivec4(child + ivec2(1, 1), node.z - 1, 0);
            }
        }
        if (!whole_node && split == 0) continue;
        vec3 weight = w.rgb;
        mat3 points = whole_node ? node_points(node) : part_points(node.xy, split, k, weight);
        total += weight * lobe_mean(points);
    }
    tops[index] = top;
    sums[sample_index] += vec4(total, 0.0);
}
#endif
#endif
