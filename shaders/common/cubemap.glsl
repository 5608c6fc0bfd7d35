// Cube map parameterization, OpenGL convention; GLSL twin of
// app/envstudio/core/cubemap.py (which draws the face layout). Faces in OpenGL
// order 0..5 = +X, -X, +Y, -Y, +Z, -Z (DESIGN.md "Conventions"); the major
// axis picks the face and the OpenGL spec table gives (sc, tc, ma):
//     +X: (-z, -y, x)  -X: (+z, -y, x)  +Y: (+x, +z, y)
//     -Y: (+x, -z, y)  +Z: (+x, -y, z)  -Z: (-x, -y, z)
//     s = (sc / |ma| + 1) / 2,  t = (tc / |ma| + 1) / 2
// Ties go to x, then y. A face texel (column j, row i) of an n x n face is
// centred at ((j + 0.5) / n, (i + 0.5) / n); row 0 is t = 0.

// Face (out) and face coordinates (s, t) of direction d (any length but zero).
vec2 cube_face_uv(vec3 d, out int face) {
    vec3 a = abs(d);
    vec3 sc_tc_ma;
    if (a.x >= a.y && a.x >= a.z) {
        face = d.x >= 0.0 ? 0 : 1;
        sc_tc_ma = vec3(d.x >= 0.0 ? -d.z : d.z, -d.y, a.x);
    } else if (a.y >= a.z) {
        face = d.y >= 0.0 ? 2 : 3;
        sc_tc_ma = vec3(d.x, d.y >= 0.0 ? d.z : -d.z, a.y);
    } else {
        face = d.z >= 0.0 ? 4 : 5;
        sc_tc_ma = vec3(d.z >= 0.0 ? d.x : -d.x, -d.y, a.z);
    }
    return (sc_tc_ma.xy / sc_tc_ma.z + 1.0) * 0.5;
}

// Unit direction of face coordinates uv on face: with (a, b) = 2 uv - 1,
// +X: (1, -b, -a)  -X: (-1, -b, a)  +Y: (a, 1, b)  -Y: (a, -1, -b)
// +Z: (a, -b, 1)   -Z: (-a, -b, -1).
vec3 cube_face_direction(int face, vec2 uv) {
    vec2 ab = 2.0 * uv - 1.0;
    vec3 d;
    if (face == 0) {
        d = vec3(1.0, -ab.y, -ab.x);
    } else if (face == 1) {
        d = vec3(-1.0, -ab.y, ab.x);
    } else if (face == 2) {
        d = vec3(ab.x, 1.0, ab.y);
    } else if (face == 3) {
        d = vec3(ab.x, -1.0, -ab.y);
    } else if (face == 4) {
        d = vec3(ab.x, -ab.y, 1.0);
    } else {
        d = vec3(-ab.x, -ab.y, -1.0);
    }
    return normalize(d);
}

// Solid angle (sr) of the spherical triangle with unit corners a, b, c (Van Oosterom
// and Strackee 1983): tan(omega / 2) = a.(b x c) / (1 + a.b + b.c + c.a), the triple
// product taken on the edge vectors so that small triangles keep their precision.
float cube_triangle_solid_angle(vec3 a, vec3 b, vec3 c) {
    float triple = dot(a, cross(b - a, c - a));
    return 2.0 * atan(abs(triple), 1.0 + dot(a, b) + dot(b, c) + dot(c, a));
}

// Exact solid angle (sr) of texel (column, row) of an n x n face (the same on every
// face). Texel edges lie on great circles, so the texel is a spherical quadrilateral:
// two triangles. (core/cubemap.py integrates the area element instead; the two agree,
// and this form keeps float32 precision for small texels.)
float cube_texel_solid_angle(ivec2 texel, int size) {
    vec2 lo = vec2(texel) / float(size);
    vec2 hi = vec2(texel + 1) / float(size);
    vec3 c00 = cube_face_direction(4, lo);
    vec3 c10 = cube_face_direction(4, vec2(hi.x, lo.y));
    vec3 c11 = cube_face_direction(4, hi);
    vec3 c01 = cube_face_direction(4, vec2(lo.x, hi.y));
    return cube_triangle_solid_angle(c00, c10, c11) + cube_triangle_solid_angle(c00, c11, c01);
}
