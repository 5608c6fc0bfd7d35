// Trilinear cube-map lookups in a PEM atlas (seed 003 section 4, "EM MIPMAPs"),
// exactly as the bake's rendering matrix weighs texels
// (app/envstudio/bake/pem/infer.py trilinear_matrix), so that inference and
// playback agree by construction. Include after common/cubemap.glsl.
//
// An atlas is one RGBA32F 2D texture holding every map of a bake in a flat
// texel order: map m (view v, part p: m = v * parts + p) starts at m * T, T =
// sum_k 6 n_k^2 with n_k = n >> k; level k starts at offset_k = sum_{j<k} 6 n_j^2;
// texel (face f, row i <-> t, column j <-> s) of level k is offset_k + f n_k^2 +
// i n_k + j. Flat index x lies at (x mod width, x div width).

uniform int u_atlas_width;
uniform int u_em_size;   // n, level 0's face edge
uniform int u_em_levels; // L, n >> (L - 1) >= 1

vec4 pem_atlas_texel(sampler2D atlas, int index) {
    return texelFetch(atlas, ivec2(index % u_atlas_width, index / u_atlas_width), 0);
}

// Bilinear lookup on one face of level k (size nk, starting at flat index base),
// the four texels clamped to the face's edge.
vec4 pem_bilinear(sampler2D atlas, int base, int nk, int face, vec2 st) {
    vec2 x = st * float(nk) - 0.5;
    vec2 x0 = floor(x);
    vec2 f = x - x0;
    int j0 = clamp(int(x0.x), 0, nk - 1);
    int j1 = clamp(int(x0.x) + 1, 0, nk - 1);
    int i0 = clamp(int(x0.y), 0, nk - 1);
    int i1 = clamp(int(x0.y) + 1, 0, nk - 1);
    int b = base + face * nk * nk;
    vec4 t00 = pem_atlas_texel(atlas, b + i0 * nk + j0);
    vec4 t01 = pem_atlas_texel(atlas, b + i0 * nk + j1);
    vec4 t10 = pem_atlas_texel(atlas, b + i1 * nk + j0);
    vec4 t11 = pem_atlas_texel(atlas, b + i1 * nk + j1);
    return mix(mix(t00, t01, f.x), mix(t10, t11, f.x), f.y);
}

// Flat offset and face edge of level k.
int pem_level_offset(int k, out int nk) {
    int offset = 0;
    nk = u_em_size;
    for (int j = 0; j < k; ++j) {
        offset += 6 * nk * nk;
        nk = nk >> 1;
    }
    return offset;
}

// Texels per map, T.
int pem_map_texels() {
    int nk;
    return pem_level_offset(u_em_levels, nk);
}

// Trilinear lookup of map `map` at face coordinates st of `face`, level lod
// (clamped to [0, L - 1]; linear between floor(lod) and the next level).
vec4 pem_trilinear(sampler2D atlas, int map, int face, vec2 st, float lod) {
    float l = clamp(lod, 0.0, float(u_em_levels - 1));
    int l0 = int(floor(l));
    int l1 = min(l0 + 1, u_em_levels - 1);
    float t = l - float(l0);
    int base = map * pem_map_texels();
    int n0, n1;
    int o0 = pem_level_offset(l0, n0);
    int o1 = pem_level_offset(l1, n1);
    vec4 a = pem_bilinear(atlas, base + o0, n0, face, st);
    if (t == 0.0) {
        return a;
    }
    return mix(a, pem_bilinear(atlas, base + o1, n1, face, st), t);
}

// Mip level of a lookup vector q per pixel: log2 of the pixel's angular footprint
// in level-0 texels, n / 2 * max(|dq^/dx|, |dq^/dy|) with q^ = q / |q| (a face
// spans 2 units of the tangent plane; hardware-like, but seamless across faces).
float pem_lod(vec3 q) {
    vec3 qh = normalize(q);
    float footprint = max(length(dFdx(qh)), length(dFdy(qh))) * 0.5 * float(u_em_size);
    return log2(max(footprint, 1e-8));
}
