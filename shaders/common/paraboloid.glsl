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

// Integral of 4 / (1 + s^2 + t^2)^2 over [0, a] x [0, b] clipped to the unit disc
// (a, b >= 0); see core/paraboloid.py texel_solid_angles for the derivation.
float paraboloid_quadrant_integral(float a, float b) {
    if (a * a + b * b <= 1.0) {
        float ka = sqrt(1.0 + a * a);
        float kb = sqrt(1.0 + b * b);
        return 2.0 * a / ka * atan(b / ka) + 2.0 * b / kb * atan(a / kb);
    }
    float ac = min(a, 1.0);
    float bc = min(b, 1.0);
    float kac = sqrt(1.0 + ac * ac);
    float kbc = sqrt(1.0 + bc * bc);
    return 2.0 * ac / kac * atan(sqrt(1.0 - ac * ac) / kac) + (asin(bc) - acos(ac))
         + 2.0 * bc / kbc * atan(sqrt(1.0 - bc * bc) / kbc);
}

float paraboloid_corner(vec2 st) {
    return sign(st.x) * sign(st.y) * paraboloid_quadrant_integral(abs(st.x), abs(st.y));
}

// Exact solid angle (sr) of texel (column, row) of either face, counting the unit disc only.
float paraboloid_texel_solid_angle(ivec2 texel, float size, float border) {
    float scale = size / (size - 2.0 * border);
    vec2 lo = (2.0 * vec2(texel) / size - 1.0) * scale;
    vec2 hi = (2.0 * vec2(texel + 1) / size - 1.0) * scale;
    return paraboloid_corner(hi) - paraboloid_corner(vec2(lo.x, hi.y))
         - paraboloid_corner(vec2(hi.x, lo.y)) + paraboloid_corner(lo);
}
