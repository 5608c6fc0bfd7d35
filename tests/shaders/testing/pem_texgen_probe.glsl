#version 330 core
// Test probe: pixel (i, 0) intersects ray i (origin and direction read from two
// RGBA32F textures) with the box and the ellipsoid of pem/texgen.glsl and writes
// (t_box, t_ellipsoid, 0, 1), so tests can compare them with the NumPy geometry of
// app/envstudio/bake/pem/infer.py.
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "pem/texgen.glsl"
uniform sampler2D u_origins;
uniform sampler2D u_directions;
uniform vec3 u_box_lo;
uniform vec3 u_box_hi;
uniform vec3 u_ellipsoid_centre;
uniform vec3 u_ellipsoid_radii;
out vec4 f_exit;

void main() {
    ivec2 texel = ivec2(gl_FragCoord.xy);
    vec3 o = texelFetch(u_origins, texel, 0).xyz;
    vec3 d = texelFetch(u_directions, texel, 0).xyz;
    f_exit = vec4(pem_box_exit(o, d, u_box_lo, u_box_hi),
                  pem_ellipsoid_exit(o, d, u_ellipsoid_centre, u_ellipsoid_radii), 0.0, 1.0);
}
#endif
