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
