// Real spherical harmonics of bands 0, 1, 2 and the even bands up to SH_ORDER: the
// bands with a non-zero clamped-cosine coefficient. GLSL twin of
// app/envstudio/core/sh_bands.py, whose docstring derives the recurrence; for
// l <= 2 the functions are seed 000 eq. 9 (common/sh.glsl).
//
// Define SH_COEFFICIENTS as 9 (order 2, the seed's), 25 (order 4) or 49 (order 6)
// before including; SH_COUNT is then the number of stored coefficients (9, 18, 31),
// per band m = -l .. l, bands in increasing order (core.sh_bands.BAND_SETS).
#include "common/sh.glsl"

#if SH_COEFFICIENTS == 9
#define SH_ORDER 2
#define SH_COUNT 9
#elif SH_COEFFICIENTS == 25
#define SH_ORDER 4
#define SH_COUNT 18
#elif SH_COEFFICIENTS == 49
#define SH_ORDER 6
#define SH_COUNT 31
#else
#error "SH_COEFFICIENTS must be 9, 25 or 49"
#endif

// Storage offset of band l (-1 for the odd bands above 1, which are not stored).
int sh_band_offset(int l) {
    if (l <= 2) {
        return l * l;
    }
    if (l % 2 == 1) {
        return -1;
    }
    return l == 4 ? 9 : 18;
}

// Band l of storage index i.
int sh_band_of(int i) {
    if (i < 9) {
        return i < 1 ? 0 : (i < 4 ? 1 : 2);
    }
    return i < 18 ? 4 : 6;
}

// Clamped-cosine coefficient A_l (seed 000 eq. 12; core.sh_bands.a_hat) of a stored band.
float sh_a_hat(int l) {
    const float PI = 3.14159265358979;
    if (l == 0) {
        return PI;
    }
    if (l == 1) {
        return 2.0 * PI / 3.0;
    }
    if (l == 2) {
        return PI / 4.0;
    }
    return l == 4 ? -PI / 24.0 : PI / 64.0;
}

// Y_i at unit direction d, storage order.
void sh_bands_basis(vec3 d, out float y[SH_COUNT]) {
#if SH_ORDER == 2
    sh9_basis(d, y);
#else
    const float FOUR_PI = 12.5663706143592;
    float re = 1.0;   // Re (x + iy)^m
    float im = 0.0;   // Im (x + iy)^m
    float pmm = 1.0;  // (2m - 1)!!
    for (int m = 0; m <= SH_ORDER; ++m) {
        if (m > 0) {
            float next_re = re * d.x - im * d.y;
            im = re * d.y + im * d.x;
            re = next_re;
            pmm *= float(2 * m - 1);
        }
        float previous = 0.0;
        float current = pmm;
        float ratio = 1.0;  // (l - m)! / (l + m)!
        for (int j = 1; j <= 2 * m; ++j) {
            ratio /= float(j);
        }
        for (int l = m; l <= SH_ORDER; ++l) {
            if (l > m) {
                float next = (float(2 * l - 1) * d.z * current - float(l + m - 1) * previous)
                             / float(l - m);
                previous = current;
                current = next;
                ratio *= float(l - m) / float(l + m);
            }
            int offset = sh_band_offset(l);
            if (offset < 0) {
                continue;
            }
            float k = sqrt(float(2 * l + 1) / FOUR_PI * ratio);
            if (m == 0) {
                y[offset + l] = k * current;
            } else {
                k *= 1.41421356237310 * current;
                y[offset + l + m] = k * re;
                y[offset + l - m] = k * im;
            }
        }
    }
#endif
}
