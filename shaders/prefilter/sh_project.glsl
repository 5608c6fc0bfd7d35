#version 430
// Method `kautz`, dynamic lighting (seed 000 section 5.1.1) on the GPU: per-tile
// partial sums of the SH projection (eq. 11) of one cube map level, and of the
// excess above the light threshold (core/sh_lights.py explains the decomposition;
// its DiffuseProjector.for_cube is the NumPy twin). One invocation per tile: the
// faces are cut into TILES_PER_EDGE^2 tiles each, tile = (face * T + row) * T + column
// with row <-> t and column <-> s, so a tile is (n / T)^2 texels of an n x n face.
// (The work is small: 6 * 64^2 texels. One invocation per tile needs no shared memory
// or barriers, which keeps it fast on software rasterisers too.)
//
// PASS 1 writes, per tile, sum_texels L Y_i dw for every coefficient and channel
//        (slot 3 i + c) and sum lum dw (slot 3 SH_COUNT): u_full[tile * SLOTS + slot].
// PASS 2 reads the tile powers of pass 1, sets the threshold T = tau * mean luminance,
//        and writes the same sums for the excess L (1 - T / lum)+ plus its luminance
//        moment sum e dw l (3), power sum e dw (1) and RGB power (3):
//        u_excess[tile * SLOTS + slot].
// Defines: PASS (1, 2), SH_COEFFICIENTS (9, 25, 49), TILES_PER_EDGE.
#if defined COMPUTE_SHADER
#include "common/cubemap.glsl"
#include "common/sh_bands.glsl"

#define TILES (6 * TILES_PER_EDGE * TILES_PER_EDGE)
#define SH_SLOTS (3 * SH_COUNT)
#define FULL_SLOTS (SH_SLOTS + 1)
#if PASS == 1
#define SLOTS FULL_SLOTS
#else
#define SLOTS (SH_SLOTS + 7)
#endif

layout(local_size_x = 64) in;
layout(rgba32f, binding = 0) readonly uniform imageCube u_cube;
layout(std430, binding = 1) buffer FullSums {
    float u_full[];
};
#if PASS == 2
layout(std430, binding = 2) writeonly buffer ExcessSums {
    float u_excess[];
};
uniform float u_threshold;
#endif
uniform int u_face_size;

const vec3 LUMINANCE = vec3(0.2126, 0.7152, 0.0722);

void main() {
    uint tile = gl_GlobalInvocationID.x;
    if (tile >= TILES) {
        return;
    }
    int face = int(tile) / (TILES_PER_EDGE * TILES_PER_EDGE);
    int cell = int(tile) % (TILES_PER_EDGE * TILES_PER_EDGE);
    int span = u_face_size / TILES_PER_EDGE;
    ivec2 origin = ivec2(cell % TILES_PER_EDGE, cell / TILES_PER_EDGE) * span;
#if PASS == 2
    float total = 0.0;  // sum over the sphere of lum dw, from the tile powers of pass 1
    for (int t = 0; t < TILES; ++t) {
        total += u_full[t * FULL_SLOTS + SH_SLOTS];
    }
    float cutoff = u_threshold * total / 12.5663706143592;
#endif
    float sums[SLOTS];
    for (int k = 0; k < SLOTS; ++k) {
        sums[k] = 0.0;
    }
    for (int row = 0; row < span; ++row) {
        for (int column = 0; column < span; ++column) {
            ivec2 texel = origin + ivec2(column, row);
            vec3 d = cube_face_direction(face, (vec2(texel) + 0.5) / float(u_face_size));
            float dw = cube_texel_solid_angle(texel, u_face_size);
            vec3 radiance = imageLoad(u_cube, ivec3(texel, face)).rgb;
            float lum = dot(radiance, LUMINANCE);
#if PASS == 1
            vec3 value = radiance * dw;
            sums[SH_SLOTS] += lum * dw;
#else
            // Above T by more than rounding (core.sh_lights._MARGIN): a constant map has no excess.
            float fraction = lum > cutoff * 1.0001 ? 1.0 - cutoff / lum : 0.0;
            if (fraction == 0.0) {
                continue;
            }
            vec3 value = radiance * fraction * dw;
            vec4 moment = lum * fraction * dw * vec4(d, 1.0);
            for (int k = 0; k < 4; ++k) {
                sums[SH_SLOTS + k] += moment[k];
            }
            for (int c = 0; c < 3; ++c) {
                sums[SH_SLOTS + 4 + c] += value[c];
            }
#endif
            float y[SH_COUNT];
            sh_bands_basis(d, y);
            for (int i = 0; i < SH_COUNT; ++i) {
                sums[3 * i] += y[i] * value.r;
                sums[3 * i + 1] += y[i] * value.g;
                sums[3 * i + 2] += y[i] * value.b;
            }
        }
    }
    for (int k = 0; k < SLOTS; ++k) {
#if PASS == 1
        u_full[tile * SLOTS + k] = sums[k];
#else
        u_excess[tile * SLOTS + k] = sums[k];
#endif
    }
}
#endif
