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

// Sobol dimensions 3 to 6 (Joe & Kuo 2008 primitive polynomials and initial
// direction numbers: x^2+x+1, m = 1,3; x^3+x+1, m = 1,3,1; x^3+x^2+1, m = 1,1,1;
// x^4+x+1, m = 1,1,3,3) as 32-bit direction numbers, 32 per dimension.
const uint SOBOL_DIRECTIONS[128] = uint[128](
    0x80000000u, 0xc0000000u, 0x60000000u, 0x90000000u, 0xe8000000u, 0x5c000000u, 0x8e000000u,
    0xc5000000u, 0x68800000u, 0x9cc00000u, 0xee600000u, 0x55900000u, 0x80680000u, 0xc09c0000u,
    0x60ee0000u, 0x90550000u, 0xe8808000u, 0x5cc0c000u, 0x8e606000u, 0xc5909000u, 0x6868e800u,
    0x9c9c5c00u, 0xeeee8e00u, 0x5555c500u, 0x8000e880u, 0xc0005cc0u, 0x60008e60u, 0x9000c590u,
    0xe8006868u, 0x5c009c9cu, 0x8e00eeeeu, 0xc5005555u,
    0x80000000u, 0xc0000000u, 0x20000000u, 0x50000000u, 0xf8000000u, 0x74000000u, 0xa2000000u,
    0x93000000u, 0xd8800000u, 0x25400000u, 0x59e00000u, 0xe6d00000u, 0x78080000u, 0xb40c0000u,
    0x82020000u, 0xc3050000u, 0x208f8000u, 0x51474000u, 0xfbea2000u, 0x75d93000u, 0xa0858800u,
    0x914e5400u, 0xdbe79e00u, 0x25db6d00u, 0x58800080u, 0xe54000c0u, 0x79e00020u, 0xb6d00050u,
    0x800800f8u, 0xc00c0074u, 0x200200a2u, 0x50050093u,
    0x80000000u, 0x40000000u, 0x20000000u, 0xb0000000u, 0xf8000000u, 0xdc000000u, 0x7a000000u,
    0x9d000000u, 0x5a800000u, 0x2fc00000u, 0xa1600000u, 0xf0b00000u, 0xda880000u, 0x6fc40000u,
    0x81620000u, 0x40bb0000u, 0x22878000u, 0xb3c9c000u, 0xfb65a000u, 0xddb2d000u, 0x78022800u,
    0x9c0b3c00u, 0x5a0fb600u, 0x2d0ddb00u, 0xa2878080u, 0xf3c9c040u, 0xdb65a020u, 0x6db2d0b0u,
    0x800228f8u, 0x400b3cdcu, 0x200fb67au, 0xb00ddb9du,
    0x80000000u, 0x40000000u, 0x60000000u, 0x30000000u, 0xc8000000u, 0x24000000u, 0x56000000u,
    0xfb000000u, 0xe0800000u, 0x70400000u, 0xa8600000u, 0x14300000u, 0x9ec80000u, 0xdf240000u,
    0xb6d60000u, 0x8bbb0000u, 0x48008000u, 0x64004000u, 0x36006000u, 0xcb003000u, 0x2880c800u,
    0x54402400u, 0xfe605600u, 0xef30fb00u, 0x7e48e080u, 0xaf647040u, 0x1eb6a860u, 0x9f8b1430u,
    0xd6c81ec8u, 0xbb249f24u, 0x80d6d6d6u, 0x40bbbbbbu);

uint sobol_table(uint index, int dimension) {
    uint result = 0u;
    for (int k = 0; index != 0u; index >>= 1u, ++k) {
        if ((index & 1u) != 0u) result ^= SOBOL_DIRECTIONS[32 * dimension + k];
    }
    return result;
}

// Point `index` of a per-pixel Owen-scrambled, shuffled 6D Sobol sequence, as
// three 2D quantities sampled jointly (the pixel footprint, the lobe and the
// environment), so their interactions are stratified too, not only each on
// its own.
void sobol6(uvec2 pixel, uint index, out vec2 first, out vec2 second, out vec2 third) {
    uvec3 seeds = pcg3d(uvec3(pixel, 0x20000u));
    uvec3 more = pcg3d(seeds);
    uvec3 most = pcg3d(more);
    uint shuffled = nested_uniform_scramble(index, seeds.x);
    uvec2 a = uvec2(nested_uniform_scramble(bitfieldReverse(shuffled), seeds.y),
                    nested_uniform_scramble(sobol_second(shuffled), seeds.z));
    uvec2 b = uvec2(nested_uniform_scramble(sobol_table(shuffled, 0), more.x),
                    nested_uniform_scramble(sobol_table(shuffled, 1), more.y));
    uvec2 c = uvec2(nested_uniform_scramble(sobol_table(shuffled, 2), more.z),
                    nested_uniform_scramble(sobol_table(shuffled, 3), most.x));
    const float scale = 1.0 / 16777216.0;
    first = vec2(a >> 8u) * scale;
    second = vec2(b >> 8u) * scale;
    third = vec2(c >> 8u) * scale;
}
