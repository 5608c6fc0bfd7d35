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
