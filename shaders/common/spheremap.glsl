// Sphere map (gazing ball, OpenGL GL_SPHERE_MAP); GLSL twin of
// app/envstudio/core/spheremap.py. Convention (DESIGN.md "Conventions"): for a
// view-space reflection r (camera looking down -Z)
//     m = 2 sqrt(rx^2 + ry^2 + (rz + 1)^2),   (s, t) = (rx / m + 0.5, ry / m + 0.5)
// The centre is +Z, the rim (radius 0.5 around (0.5, 0.5)) is the singular
// direction (0, 0, -1). The map is equal-area: d omega = 16 ds dt in the disc.
// Row 0 is t = 0, the bottom of the ball.

#include "common/paraboloid.glsl"

// Texture coordinates of view-space direction r (any length but zero); (0, 0, -1)
// gives the rim point (0.5, 0).
vec2 spheremap_uv(vec3 r) {
    r = normalize(r);
    float m = 2.0 * sqrt(r.x * r.x + r.y * r.y + (r.z + 1.0) * (r.z + 1.0));
    return m > 0.0 ? r.xy / m + 0.5 : vec2(0.5, 0.0);
}

// View-space unit direction of texture coordinates uv: with (p, q) = 2 uv - 1 and
// nz = sqrt(1 - p^2 - q^2), r = (2 nz p, 2 nz q, 2 nz^2 - 1); (0, 0, -1) on and
// outside the rim.
vec3 spheremap_direction(vec2 uv) {
    vec2 pq = 2.0 * uv - 1.0;
    float nz = sqrt(max(1.0 - dot(pq, pq), 0.0));
    return vec3(2.0 * nz * pq, 2.0 * nz * nz - 1.0);
}

// Solid angle (sr) of texel (column, row) of an n x n sphere map: 4 times the texel's
// area in (p, q) inside the unit disc (16 / n^2 wholly inside, 0 outside); the rim
// texels' clipped areas come from paraboloid_disc_integral with w = 0.
float spheremap_texel_solid_angle(ivec2 texel, int size) {
    vec2 lo = 2.0 * vec2(texel) / float(size) - 1.0;
    vec2 hi = 2.0 * vec2(texel + 1) / float(size) - 1.0;
    return paraboloid_disc_integral(lo, hi, 0.0);
}
