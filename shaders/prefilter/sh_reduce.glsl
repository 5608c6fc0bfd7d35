#version 430
// Method `kautz`, dynamic lighting on the GPU: sums the tile partials of
// prefilter/sh_project.glsl into the uniform block of common/sh_irradiance.glsl (one work group).
// With LIGHTS > 0 the tiles are ranked by excess power (ties by tile index, as
// numpy's stable argsort); the LIGHTS strongest with non-zero power become cap
// lights and their excess leaves the SH sum; the rest stays in it
// (core.sh_lights.DiffuseProjector.project is the NumPy twin). Output rows:
//   u_rows[i]                    vec4(A_l L_i, 0)      i < SH_COUNT
//   u_rows[SH_COUNT + k]         vec4(direction, sin^2 alpha)
//   u_rows[SH_COUNT + LIGHTS + k] vec4(rgb moment magnitude, 0)
// Defines: SH_COEFFICIENTS (9, 25, 49), LIGHTS (0 .. 32), TILES_PER_EDGE.
#if defined COMPUTE_SHADER
#include "common/sh_bands.glsl"

#define GROUP 256
#define TILES (6 * TILES_PER_EDGE * TILES_PER_EDGE)
#define SH_SLOTS (3 * SH_COUNT)
#define FULL_STRIDE (SH_SLOTS + 1)
#define EXCESS_STRIDE (SH_SLOTS + 7)
// Caps stay below a half-angle of 84 degrees (core.sh_lights.MAX_SIN2_ALPHA).
#define MAX_SIN2_ALPHA 0.99

layout(local_size_x = GROUP) in;
layout(std430, binding = 1) readonly buffer FullSums {
    float u_full[];
};
layout(std430, binding = 3) writeonly buffer ShIrradianceRows {
    vec4 u_rows[];
};
#if LIGHTS > 0
layout(std430, binding = 2) readonly buffer ExcessSums {
    float u_excess[];
};
shared float s_power[TILES];
shared bool s_selected[TILES];
#endif

void main() {
    uint lane = gl_LocalInvocationIndex;
#if LIGHTS > 0
    for (uint t = lane; t < TILES; t += GROUP) {
        s_power[t] = u_excess[t * EXCESS_STRIDE + SH_SLOTS + 3];
    }
    barrier();
    for (uint t = lane; t < TILES; t += GROUP) {
        float power = s_power[t];
        uint rank = 0u;
        for (uint u = 0u; u < TILES; ++u) {
            rank += (s_power[u] > power || (s_power[u] == power && u < t)) ? 1u : 0u;
        }
        bool selected = rank < LIGHTS && power > 0.0;
        s_selected[t] = selected;
        if (rank < LIGHTS) {
            vec4 direction = vec4(0.0);
            vec3 rgb = vec3(0.0);
            if (selected) {
                uint base = t * EXCESS_STRIDE + SH_SLOTS;
                vec3 moment = vec3(u_excess[base], u_excess[base + 1u], u_excess[base + 2u]);
                float magnitude = length(moment);
                float cos_alpha = clamp(2.0 * magnitude / power - 1.0, 0.0, 1.0);
                float sin2 = min(1.0 - cos_alpha * cos_alpha, MAX_SIN2_ALPHA);
                direction = vec4(moment / magnitude, sin2);
                rgb = vec3(u_excess[base + 4u], u_excess[base + 5u], u_excess[base + 6u])
                      * (magnitude / power);
            }
            u_rows[SH_COUNT + rank] = direction;
            u_rows[SH_COUNT + LIGHTS + rank] = vec4(rgb, 0.0);
        }
    }
    barrier();
#endif
    for (uint slot = lane; slot < SH_SLOTS; slot += GROUP) {
        float sum = 0.0;
        for (uint t = 0u; t < TILES; ++t) {
            sum += u_full[t * FULL_STRIDE + slot];
#if LIGHTS > 0
            if (s_selected[t]) {
                sum -= u_excess[t * EXCESS_STRIDE + slot];
            }
#endif
        }
        int i = int(slot) / 3;
        u_rows[i][slot % 3u] = sh_a_hat(sh_band_of(i)) * sum;
        if (slot % 3u == 0u) {
            u_rows[i].w = 0.0;
        }
    }
}
#endif
