// Display path (DESIGN.md): exposure, tone map (none, Reinhard, ACES), sRGB encode.
#define TONEMAP_NONE 0
#define TONEMAP_REINHARD 1
#define TONEMAP_ACES 2

vec3 tonemap(vec3 c, int mode) {
    if (mode == TONEMAP_REINHARD) {
        return c / (1.0 + c);
    }
    if (mode == TONEMAP_ACES) {
        // Narkowicz 2015 fit of the ACES RRT+ODT.
        return clamp((c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14), 0.0, 1.0);
    }
    return c;
}

vec3 srgb_encode(vec3 linear) {
    vec3 c = clamp(linear, 0.0, 1.0);
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
