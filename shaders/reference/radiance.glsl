// Incident radiance along a ray for the reference: the environment at
// infinity (full-resolution lat-long, each texel constant over its solid
// angle, as the brute-force sums of prefilter/brute_force.py assume), or, with
// TRACE_LOCAL = 1, the scene's triangles traced first (reference/paths.glsl).
// Needs reference/material.glsl and common/random.glsl.
uniform sampler2D u_latlong;

vec3 environment_radiance(vec3 l) {
    ivec2 size = textureSize(u_latlong, 0);
    ivec2 texel = clamp(ivec2(latlong_uv(l) * vec2(size)), ivec2(0), size - 1);
    return texelFetch(u_latlong, texel, 0).rgb;
}

#include "reference/trace.glsl"
#include "reference/paths.glsl"
#include "reference/footprint.glsl"

vec3 incident(vec3 p, vec3 n, vec3 l) {
#if TRACE_LOCAL
    return traced_radiance(p, n, l);
#else
    return environment_radiance(l);
#endif
}
