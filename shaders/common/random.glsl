// PCG-style integer hash random numbers (Jarzynski & Olano 2020, "Hash
// Functions for GPU Rendering", pcg3d). One state per pixel, frame and sample.
uvec3 pcg3d(uvec3 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.z; v.y += v.z * v.x; v.z += v.x * v.y;
    v ^= v >> 16u;
    v.x += v.y * v.z; v.y += v.z * v.x; v.z += v.x * v.y;
    return v;
}

// Two uniform numbers in [0, 1) for (pixel, frame, sample index).
vec2 random2(uvec2 pixel, uint frame, uint index) {
    uvec3 h = pcg3d(uvec3(pixel.x, pixel.y, frame * 65536u + index));
    return vec2(h.xy >> 8u) * (1.0 / 16777216.0);
}

// Randomised quasi-Monte Carlo: point `index` of the R2 sequence (Roberts 2018,
// additive recurrence with the plastic number) shifted by a random offset per
// (pixel, batch, technique) — Cranley-Patterson rotation. Points within a batch
// are stratified; batches stay independent, so the spread of batch means is
// still an honest error estimate.
vec2 stratified2(uvec2 pixel, uint batch, uint technique, uint index) {
    const vec2 alpha = vec2(0.7548776662466927, 0.5698402909980532);
    vec2 shift = random2(pixel, batch, 0x10000u + technique);
    return fract(shift + float(index) * alpha);
}
