#version 330 core
// One source map warped into the destination map and accumulated (seed 002 §3.2-§3.4, §4).
// The destination sphere map is drawn as a tessellated disk (§3.3): each vertex
// is a destination point p_d, and its texture coordinate in the source map is
// the inverse of the composed warp of app/envstudio/methods/rsibr/warp.py,
//     p_s = g^-1(M g(p_d)),   M = T_s^-1 T_d (destination-local -> source-local),
// with g = g_mirror (u_warp 0) or g_normal (u_warp 1). With u_per_pixel it is
// evaluated per fragment instead (the per-pixel warp of §6's future work).
// Points beyond the disc take the value of the rim point at their angle (just
// inside it, where g_mirror is still invertible).
// Output: (w L, w) with additive blending into a float target (the accumulation
// buffer of §4), w = the barycentric weight times the singularity fade (§3.3):
// mirror warp, smoothstep of the distance in the destination map from the
// source's singular point u_singularity = g_mirror^-1(T_d^-1 (-v_s)); normal
// warp, smoothstep of the source-local normal's z (the source holds n.v_s > 0).
#define RIM 0.49995
vec2 rim_clamped(vec2 uv) {
    vec2 d = uv - 0.5;
    float rho = length(d);
    return rho > RIM ? 0.5 + d * (RIM / rho) : uv;
}

// g of the warp: destination point -> map-local direction (§3.3).
vec3 g_of(vec2 uv, int warp) {
    vec2 pq = 2.0 * uv - 1.0;
    float nz = sqrt(max(1.0 - dot(pq, pq), 0.0));
    return warp == 0 ? vec3(2.0 * nz * pq, 2.0 * nz * nz - 1.0) : vec3(pq, nz);
}

// g^-1 of the warp: map-local direction -> point (§3.3).
vec2 g_inverse_of(vec3 d, int warp) {
    d = normalize(d);
    vec3 n = warp == 0 ? d + vec3(0.0, 0.0, 1.0) : d;
    float len = length(n);
    return len > 0.0 ? 0.5 * n.xy / len + 0.5 : vec2(0.5, 0.0);
}

uniform mat3 u_dest_to_source;
uniform int u_warp;
uniform bool u_per_pixel;

#if defined VERTEX_SHADER
in vec2 in_uv;
out vec2 v_uv_d;
out vec2 v_uv_s;
out float v_source_z;
void main() {
    v_uv_d = in_uv;
    vec3 d = u_dest_to_source * g_of(rim_clamped(in_uv), u_warp);
    v_uv_s = g_inverse_of(d, u_warp);
    v_source_z = normalize(d).z;
    gl_Position = vec4(2.0 * in_uv - 1.0, 0.0, 1.0);
}
#elif defined FRAGMENT_SHADER
uniform sampler2D u_source;
uniform float u_weight;
uniform bool u_fade;
uniform float u_fade_radius;
uniform vec2 u_singularity;
in vec2 v_uv_d;
in vec2 v_uv_s;
in float v_source_z;
out vec4 f_color;
void main() {
    vec2 uv_s = v_uv_s;
    float source_z = v_source_z;
    if (u_per_pixel) {
        vec3 d = u_dest_to_source * g_of(rim_clamped(v_uv_d), u_warp);
        uv_s = g_inverse_of(d, u_warp);
        source_z = normalize(d).z;
    }
    float confidence = 1.0;
    if (u_fade) {
        confidence = u_warp == 0
            ? smoothstep(0.0, u_fade_radius, distance(v_uv_d, u_singularity))
            : smoothstep(0.0, u_fade_radius, source_z);
    }
    float w = u_weight * max(confidence, 1e-4);
    f_color = vec4(w * textureLod(u_source, uv_s, 0.0).rgb, w);
}
#endif
