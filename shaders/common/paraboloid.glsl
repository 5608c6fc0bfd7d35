// Dual-paraboloid parameterization (Heidrich and Seidel 1998); GLSL twin of
// app/envstudio/core/paraboloid.py. Convention (DESIGN.md "Conventions"):
//     face 0 (front), z >= 0: (s, t) = (x, y) / (1 + z)
//     face 1 (back),  z <  0: (s, t) = (x, y) / (1 - z)
// The unit disc spans the central n - 2B texels of an n x n face with a border
// of B texels: tex = 0.5 + 0.5 * s * (n - 2B) / n. Inverse (also beyond the
// disc, into the border): d = (2s, 2t, +-(1 - s^2 - t^2)) / (1 + s^2 + t^2).
// The two faces are layers 0 and 1 of a sampler2DArray; row 0 is t = 0.

// Texture coordinates of direction d (any length but zero) and its face (out).
vec2 paraboloid_uv(vec3 d, float size, float border, out int face) {
    d = normalize(d);
    face = d.z >= 0.0 ? 0 : 1;
    vec2 st = d.xy / (1.0 + abs(d.z));
    return 0.5 + 0.5 * st * (size - 2.0 * border) / size;
}

// Unit direction of texture coordinates uv on face (0 front, 1 back).
vec3 paraboloid_direction(int face, vec2 uv, float size, float border) {
    vec2 st = (2.0 * uv - 1.0) * size / (size - 2.0 * border);
    float r2 = dot(st, st);
    float z = (face == 0 ? 1.0 : -1.0) * (1.0 - r2);
    return vec3(2.0 * st, z) / (1.0 + r2);
}

// Filtered lookup of direction d in a dual-paraboloid map (layers 0 and 1) at mip level lod.
vec4 paraboloid_texture_lod(sampler2DArray maps, vec3 d, float border, float lod) {
    int face;
    vec2 uv = paraboloid_uv(d, float(textureSize(maps, 0).x), border, face);
    return textureLod(maps, vec3(uv, float(face)), lod);
}

// Integral of 4 / (1 + w (s^2 + t^2))^2 over the rectangle [lo, hi] clipped to the unit
// disc: the dual paraboloid's solid-angle element for w = 1, the sphere map's (4 dp dq)
// for w = 0. core/paraboloid.py and core/spheremap.py evaluate it in closed form; in
// float32 that form cancels O(1) terms, so here it is integrated numerically instead:
// over s in pieces split where the t limits switch between the rectangle's edges and
// the rim (s = +-sqrt(1 - t^2)), each piece smooth, by 4-point Gauss-Legendre in s and
// in t. The integrand is symmetric in s and t, so the outer variable is taken as the
// one nearer the centre, where the rim is at most 45 degrees steep (elsewhere its
// square-root shape would spoil the quadrature). Precise to float32 rounding of
// texel-sized terms.
float paraboloid_disc_integral(vec2 lo, vec2 hi, float w) {
    if (max(abs(lo.x), abs(hi.x)) > max(abs(lo.y), abs(hi.y))) {
        lo = lo.yx;
        hi = hi.yx;
    }
    const vec4 node = vec4(-0.8611363115940526, -0.3399810435848563,
                           0.3399810435848563, 0.8611363115940526);
    const vec4 weight = vec4(0.3478548451374538, 0.6521451548625461,
                             0.6521451548625461, 0.3478548451374538);
    float s_lo = max(lo.x, -1.0);
    float s_hi = min(hi.x, 1.0);
    if (s_lo >= s_hi) {
        return 0.0;
    }
    float cuts[6];
    int count = 1;
    cuts[0] = s_lo;
    for (int k = 0; k < 2; ++k) {
        float t = k == 0 ? lo.y : hi.y;
        float c = sqrt(max((1.0 - t) * (1.0 + t), 0.0));
        if (-c > s_lo && -c < s_hi) {
            cuts[count++] = -c;
        }
        if (c > s_lo && c < s_hi && c > 0.0) {
            cuts[count++] = c;
        }
    }
    cuts[count++] = s_hi;
    for (int i = 1; i < count; ++i) {  // insertion sort of the piece boundaries
        float v = cuts[i];
        int j = i - 1;
        while (j >= 0 && cuts[j] > v) {
            cuts[j + 1] = cuts[j];
            --j;
        }
        cuts[j + 1] = v;
    }
    float total = 0.0;
    for (int k = 0; k + 1 < count; ++k) {
        float mid = 0.5 * (cuts[k] + cuts[k + 1]);
        float half_width = 0.5 * (cuts[k + 1] - cuts[k]);
        for (int i = 0; i < 4; ++i) {
            float s = mid + half_width * node[i];
            float c = sqrt(max((1.0 - s) * (1.0 + s), 0.0));
            float t_lo = max(lo.y, -c);
            float t_hi = min(hi.y, c);
            if (t_hi <= t_lo) {
                continue;
            }
            float inner = 0.0;
            for (int j = 0; j < 4; ++j) {
                float t = 0.5 * (t_lo + t_hi) + 0.5 * (t_hi - t_lo) * node[j];
                float k2 = 1.0 + w * (s * s + t * t);
                inner += weight[j] * 4.0 / (k2 * k2);
            }
            total += weight[i] * half_width * 0.5 * (t_hi - t_lo) * inner;
        }
    }
    return total;
}

// Solid angle (sr) of texel (column, row) of either face, counting the unit disc only
// (0 for texels wholly in the border).
float paraboloid_texel_solid_angle(ivec2 texel, float size, float border) {
    float scale = size / (size - 2.0 * border);
    vec2 lo = (2.0 * vec2(texel) / size - 1.0) * scale;
    vec2 hi = (2.0 * vec2(texel + 1) / size - 1.0) * scale;
    return paraboloid_disc_integral(lo, hi, 1.0);
}
