// Randomised quasi-Monte Carlo, one sequence per pixel: point `index` of a
// per-(pixel, technique) Owen-scrambled, index-shuffled 2D Sobol sequence
// (Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4)). The index
// runs on across batches (index = batch * samples + sample), so every power-of-
// two prefix of a pixel's samples is a scrambled (0, m, 2)-net: errors fall
// faster than 1/sqrt(n) for the piecewise-smooth integrands of the reference.
// Different techniques get independent scrambles and shuffles (padding), so
// their dimensions are not correlated. Needs GLSL 4.00 (bitfieldReverse) and
// common/random.glsl (pcg3d).
uint laine_karras_permutation(uint x, uint seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

uint nested_uniform_scramble(uint x, uint seed) {
    return bitfieldReverse(laine_karras_permutation(bitfieldReverse(x), seed));
}

// Second Sobol dimension (primitive polynomial x + 1): direction numbers
// v_k = v_{k-1} ^ (v_{k-1} >> 1), v_1 = 2^31. The first is the van der Corput
// radical inverse, bitfieldReverse(index).
uint sobol_second(uint index) {
    uint v = 0x80000000u;
    uint result = 0u;
    for (; index != 0u; index >>= 1u) {
        if ((index & 1u) != 0u) result ^= v;
        v ^= v >> 1u;
    }
    return result;
}

vec2 sobol2(uvec2 pixel, uint technique, uint index) {
    uvec3 seeds = pcg3d(uvec3(pixel, 0x10000u + technique));
    uint shuffled = nested_uniform_scramble(index, seeds.x);
    uint x = nested_uniform_scramble(bitfieldReverse(shuffled), seeds.y);
    uint y = nested_uniform_scramble(sobol_second(shuffled), seeds.z);
    return vec2(uvec2(x, y) >> 8u) * (1.0 / 16777216.0);
}
