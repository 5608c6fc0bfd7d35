// Direction sampling for the reference estimator (methods/reference.py).
// Frames: local frame around a unit axis; lobes: cosine (diffuse, seed 000
// eq. 4), normalised Phong (eq. 7), GGX normals; environment: luminance CDF
// tables of core/env_sampling.py (marginal rows, conditional columns, p_uv).
#include "common/latlong.glsl"

const float PI = 3.14159265358979;

mat3 frame_around(vec3 axis) {
    vec3 helper = abs(axis.y) < 0.999 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    vec3 t = normalize(cross(helper, axis));
    return mat3(t, cross(axis, t), axis);
}

// The balance heuristic's weight (Veach 1995) of a technique of density a against one of b.
float balance(float a, float b) { return a / max(a + b, 1e-30); }

// Cosine-weighted hemisphere about n: pdf = max(n.l, 0) / pi.
vec3 sample_cosine(vec3 n, vec2 xi) {
    float r = sqrt(xi.x);
    float phi = 2.0 * PI * xi.y;
    return frame_around(n) * vec3(r * cos(phi), r * sin(phi), sqrt(max(1.0 - xi.x, 0.0)));
}

// Normalised Phong lobe about r: pdf = (N + 1) / 2pi * max(r.l, 0)^N.
vec3 sample_phong(vec3 r, float N, vec2 xi) {
    float c = pow(1.0 - xi.x, 1.0 / (N + 1.0));
    float s = sqrt(max(1.0 - c * c, 0.0));
    float phi = 2.0 * PI * xi.y;
    return frame_around(r) * vec3(s * cos(phi), s * sin(phi), c);
}

float phong_lobe(vec3 r, vec3 l, float N) {
    return (N + 1.0) / (2.0 * PI) * pow(max(dot(r, l), 0.0), N);
}

// GGX (Trowbridge-Reitz) normal distribution and a half vector drawn with pdf D(h) (n.h).
float ggx_d(float n_dot_h, float alpha) {
    float a2 = alpha * alpha;
    float d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

vec3 sample_ggx_half(vec3 n, float alpha, vec2 xi) {
    float tan2 = alpha * alpha * xi.x / max(1.0 - xi.x, 1e-7);
    float c = 1.0 / sqrt(1.0 + tan2);
    float s = sqrt(max(1.0 - c * c, 0.0));
    float phi = 2.0 * PI * xi.y;
    return frame_around(n) * vec3(s * cos(phi), s * sin(phi), c);
}

// Height-correlated Smith masking-shadowing for GGX (Heitz 2014).
float ggx_g2(float n_dot_l, float n_dot_v, float alpha) {
    float a2 = alpha * alpha;
    float gl = n_dot_v * sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2);
    float gv = n_dot_l * sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2);
    return 2.0 * n_dot_l * n_dot_v / max(gl + gv, 1e-9);
}

// ---- environment luminance sampling --------------------------------------
uniform sampler2D u_env_marginal;     // (H + 1) x 1, R32F
uniform sampler2D u_env_conditional;  // (W + 1) x H, R32F
uniform sampler2D u_env_pdf_uv;       // W x H, R32F, p_uv = w / sum(w) * W * H

float env_pdf(vec3 l) {
    ivec2 size = textureSize(u_env_pdf_uv, 0);
    vec2 uv = latlong_uv(l);
    ivec2 texel = clamp(ivec2(uv * vec2(size)), ivec2(0), size - 1);
    float p_uv = texelFetch(u_env_pdf_uv, texel, 0).r;
    float sin_theta = sqrt(max(1.0 - l.y * l.y, 1e-12));
    return p_uv / (2.0 * PI * PI * sin_theta);
}

vec3 sample_environment(vec2 xi) {
    ivec2 size = textureSize(u_env_pdf_uv, 0);
    int lo = 0;
    int hi = size.y;  // marginal has H + 1 entries; find last i with cdf[i] <= xi.y
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (texelFetch(u_env_marginal, ivec2(mid, 0), 0).r <= xi.y) lo = mid; else hi = mid;
    }
    int row = lo;
    float c0 = texelFetch(u_env_marginal, ivec2(row, 0), 0).r;
    float c1 = texelFetch(u_env_marginal, ivec2(row + 1, 0), 0).r;
    float v = (float(row) + (xi.y - c0) / max(c1 - c0, 1e-30)) / float(size.y);
    lo = 0;
    hi = size.x;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (texelFetch(u_env_conditional, ivec2(mid, row), 0).r <= xi.x) lo = mid; else hi = mid;
    }
    c0 = texelFetch(u_env_conditional, ivec2(lo, row), 0).r;
    c1 = texelFetch(u_env_conditional, ivec2(lo + 1, row), 0).r;
    float u = (float(lo) + (xi.x - c0) / max(c1 - c0, 1e-30)) / float(size.x);
    return latlong_direction(vec2(u, clamp(v, 1e-6, 1.0 - 1e-6)));
}

// ---- environment sampling restricted to a cone (the glossy lobe) ----------
// The luminance tables above, restricted to the lat-long texels of the cap's
// bounding rectangle: rows [row0, row0 + rows), columns [col0, col0 + cols)
// modulo W. A texel's probability is its global one divided by the
// rectangle's share `total`, so pdf_cone(l) = env_pdf(l) / total inside the
// rectangle and 0 outside. Under studio-like maps (a few small lamps), global
// sampling draws the lamp a lobe sees only in proportion to its share of all
// the light (12 % for studio's smallest); restricted to the lobe it is drawn
// almost always.
#define CONE_MAX_ROWS 128

float g_cone_cdf[CONE_MAX_ROWS + 1];  // cumulative restricted row shares
int g_cone_row0;
int g_cone_rows;
int g_cone_col0;
int g_cone_cols;
float g_cone_total;

// x modulo width for -width <= x < 2 width (GLSL leaves % of negatives undefined).
int wrap_column(int x, int width) {
    return x < 0 ? x + width : (x >= width ? x - width : x);
}

// Share of row `row`'s weight inside the rectangle's columns (wrapping at W).
float cone_row_fraction(int row, int width) {
    if (g_cone_cols >= width) return 1.0;
    float start = texelFetch(u_env_conditional, ivec2(g_cone_col0, row), 0).r;
    int end = g_cone_col0 + g_cone_cols;
    if (end <= width) return texelFetch(u_env_conditional, ivec2(end, row), 0).r - start;
    return 1.0 - start + texelFetch(u_env_conditional, ivec2(end - width, row), 0).r;
}

// Restrict environment sampling to the cap {l : axis.l >= cos_radius}; false
// when the cap spans more than CONE_MAX_ROWS rows or holds no weight (then the
// caller samples the whole map).
bool setup_cone(vec3 axis, float cos_radius) {
    ivec2 size = textureSize(u_env_pdf_uv, 0);
    vec2 uv = latlong_uv(axis);
    float theta = PI * uv.y;
    float radius = acos(clamp(cos_radius, -1.0, 1.0));
    int row0 = clamp(int(floor((theta - radius) / PI * float(size.y))), 0, size.y);
    int row1 = clamp(int(ceil((theta + radius) / PI * float(size.y))), 0, size.y);
    g_cone_row0 = row0;
    g_cone_rows = row1 - row0;
    if (g_cone_rows > CONE_MAX_ROWS || g_cone_rows <= 0) return false;
    g_cone_cols = size.x;
    g_cone_col0 = 0;
    if (theta - radius > 0.0 && theta + radius < PI) {
        // A cap not holding a pole spans |dphi| <= asin(sin(radius) / sin(theta)).
        float half_u = asin(min(sin(radius) / sin(theta), 1.0)) / (2.0 * PI);
        int col0 = int(floor((uv.x - half_u) * float(size.x)));
        int col1 = int(ceil((uv.x + half_u) * float(size.x)));
        if (col1 - col0 < size.x) {
            g_cone_cols = col1 - col0;
            g_cone_col0 = wrap_column(col0, size.x);
        }
    }
    g_cone_cdf[0] = 0.0;
    float below = texelFetch(u_env_marginal, ivec2(row0, 0), 0).r;
    for (int k = 0; k < g_cone_rows; ++k) {
        float above = texelFetch(u_env_marginal, ivec2(row0 + k + 1, 0), 0).r;
        g_cone_cdf[k + 1] = g_cone_cdf[k] + (above - below) * cone_row_fraction(row0 + k, size.x);
        below = above;
    }
    g_cone_total = g_cone_cdf[g_cone_rows];
    return g_cone_total > 0.0;
}

float cone_pdf(vec3 l) {
    ivec2 size = textureSize(u_env_pdf_uv, 0);
    ivec2 texel = clamp(ivec2(latlong_uv(l) * vec2(size)), ivec2(0), size - 1);
    int row = texel.y - g_cone_row0;
    int column = wrap_column(texel.x - g_cone_col0, size.x);
    if (row < 0 || row >= g_cone_rows || column >= g_cone_cols) return 0.0;
    return env_pdf(l) / g_cone_total;
}

vec3 sample_cone(vec2 xi) {
    ivec2 size = textureSize(u_env_pdf_uv, 0);
    float target = xi.y * g_cone_total;
    int lo = 0;
    int hi = g_cone_rows;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (g_cone_cdf[mid] <= target) lo = mid; else hi = mid;
    }
    int row = g_cone_row0 + lo;
    float within_row = (target - g_cone_cdf[lo]) / max(g_cone_cdf[lo + 1] - g_cone_cdf[lo], 1e-30);
    float v = (float(row) + clamp(within_row, 0.0, 1.0)) / float(size.y);
    float start = g_cone_cols >= size.x
        ? 0.0 : texelFetch(u_env_conditional, ivec2(g_cone_col0, row), 0).r;
    float s = start + xi.x * cone_row_fraction(row, size.x);
    if (s >= 1.0) s -= 1.0;
    lo = 0;
    hi = size.x;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (texelFetch(u_env_conditional, ivec2(mid, row), 0).r <= s) lo = mid; else hi = mid;
    }
    float c0 = texelFetch(u_env_conditional, ivec2(lo, row), 0).r;
    float c1 = texelFetch(u_env_conditional, ivec2(lo + 1, row), 0).r;
    float u = (float(lo) + clamp((s - c0) / max(c1 - c0, 1e-30), 0.0, 1.0)) / float(size.x);
    return latlong_direction(vec2(u, clamp(v, 1e-6, 1.0 - 1e-6)));
}
