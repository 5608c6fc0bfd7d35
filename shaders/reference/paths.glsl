// Radiance arriving at a reflector point along a traced path (reference/trace.glsl).
// Needs reference/material.glsl and common/random.glsl; environment_radiance()
// comes from radiance.glsl.
//
// Directions below the surface (the part of the eq. 7 lobe under the horizon)
// are blocked by the surface itself: no light arrives from inside the object
// (seed 000 eq. 1 integrates over the hemisphere above the surface; without
// tracing the lobe is left whole, as the prefiltered-map methods use it).
// "Below" is below the shading normal's plane or below the triangle's own
// plane, whichever cuts more: a direction under the face enters the mesh, as
// a path tracer finds by intersecting it (bunny, direct light at n.v 0.1-0.5:
// 2.1-2.2 % brighter than Mitsuba with the shading plane alone). A
// local object returns its diffuse radiance albedo/pi * E_sh9(n), as the frame
// draws it. A reflector hit continues with the material's own BRDF, sampled as
// at the first hit (material.glsl), as a path tracer does: up to
// u_trace_bounces hits, then black, so self-reflections see the room and not
// the environment behind its walls. The bound is a uniform so that no
// compiler unrolls the loop into one copy of the traversal per bounce.
//
// At each reflector hit whose continuation is traced, the environment is also
// sampled (next-event estimation): one direction drawn from the luminance tables,
// traced as a shadow ray and weighted against the BRDF's continuation by the
// balance heuristic (Veach 1995), as the first hit pairs its samples
// (accumulate.glsl). Without it a self-reflection of a small bright lamp is
// found only when the continuation happens to hit the lamp: a N = 10 knot under
// studio.exr then kept 47 % of parallax's error as noise after 2640 spp.
// Shadow rays and path rays take turns through the one trace_closest() call.
#include "common/sh.glsl"

uniform vec3 u_sh9[9];
uniform float u_ray_offset;
uniform int u_trace_bounces;

// The path's random numbers: set per estimate by the caller (pixel, sample
// number); each bounce draws the next stream.
uvec2 g_path_pixel;
uint g_path_sample;
uint g_path_stream;
// The face normal at the first hit, on the side the camera sees (set by the caller).
vec3 g_path_face;

vec3 path_random3() {
    uvec3 h = pcg3d(uvec3(g_path_pixel.x ^ (g_path_stream << 16u), g_path_pixel.y, g_path_sample));
    g_path_stream += 1u;
    return vec3(h >> 8u) * (1.0 / 16777216.0);
}

vec3 traced_radiance(vec3 p, vec3 n, vec3 l) {
    if (dot(n, l) <= 0.0 || dot(g_path_face, l) <= 0.0) return vec3(0.0);
    vec3 origin = p + n * u_ray_offset;
    vec3 direction = l;
    vec3 throughput = vec3(1.0);
    vec3 radiance = vec3(0.0);
    // the density the last reflector hit drew `direction` with (0: the first ray, or a
    // mirror, which no environment sample can draw)
    float lobe_pdf = 0.0;
    // the pending environment sample of the last hit: its direction and weight
    vec3 shadow_direction = vec3(0.0);
    vec3 shadow_weight = vec3(0.0);
    bool continues = true;
    int rays = 0;
    for (int step = 0; step < 2 * u_trace_bounces; ++step) {
        bool shadow = any(greaterThan(shadow_weight, vec3(0.0)));
        vec3 ray = shadow ? shadow_direction : direction;
        float t;
        int tri;
        vec2 uv;
        bool hit = trace_closest(origin, ray, t, tri, uv);
        if (shadow) {
            if (!hit) radiance += shadow_weight * environment_radiance(ray);
            shadow_weight = vec3(0.0);
            if (!continues) return radiance;
            continue;
        }
        ++rays;
        if (!hit) {
            float w = lobe_pdf > 0.0 ? balance(lobe_pdf, env_pdf(direction)) : 1.0;
            return radiance + throughput * w * environment_radiance(direction);
        }
        vec3 hit_normal = hit_shading_normal(tri, uv);
        vec4 info = trace_triangles[7 * tri + 6];
        if (info.a < 0.5) {
            if (dot(hit_normal, direction) > 0.0) hit_normal = -hit_normal;
            return radiance
                   + throughput * info.rgb / PI * max(sh9_irradiance(u_sh9, hit_normal), vec3(0.0));
        }
        // a reflector: the side of the face the path arrives at, as at the first hit
        vec3 face = hit_face_normal(tri);
        if (dot(face, direction) > 0.0) {
            face = -face;
            hit_normal = -hit_normal;
        }
        // the last hit a path may have: its continuation would not be traced (black)
        if (dot(hit_normal, direction) >= 0.0 || rays == u_trace_bounces) return radiance;
        vec3 weight;
        vec3 next = sample_reflector(direction, hit_normal, path_random3(), weight, lobe_pdf);
        if (lobe_pdf > 0.0) {
            // next-event estimation; the surface blocks what lies below it, as at the first hit
            vec3 toward = sample_environment(path_random3().xy);
            float environment = env_pdf(toward);
            float response_pdf;
            vec3 response = reflector_response(direction, hit_normal, toward, response_pdf);
            if (environment > 0.0 && dot(toward, face) > 0.0) {
                shadow_direction = toward;
                shadow_weight = throughput * response / environment
                                * balance(environment, response_pdf);
            }
        }
        // the surface blocks what the lobe reaches below it, as at the first hit
        bool none = all(lessThanEqual(weight, vec3(0.0)));
        continues = !(none || dot(next, hit_normal) <= 0.0 || dot(next, face) <= 0.0);
        if (!continues && all(lessThanEqual(shadow_weight, vec3(0.0)))) return radiance;
        throughput *= weight;
        origin = origin + t * direction + hit_normal * u_ray_offset;
        direction = next;
    }
    return radiance;
}
