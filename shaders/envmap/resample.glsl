#version 330 core
// Resamples one sphere parameterization into another: every fragment is one
// target texel, whose direction is looked up in the source (bilinear, mip level
// u_source_lod). The NumPy reference is app/envstudio/core/resample.py;
// conventions are those of shaders/common/*.glsl (DESIGN.md "Conventions").
//
// Defines: SOURCE and TARGET, each one of the ENVMAP_* codes below.
// Uniforms:
//   u_source           sampler2D (lat-long, sphere map), samplerCube or
//                      sampler2DArray (dual paraboloid, layers 0 and 1)
//   u_source_lod       mip level to read
//   u_source_border    paraboloid source border B in texels
//   u_target_size      target face size in texels (w, h)
//   u_target_face      cube face 0..5 or paraboloid face 0..1 being rendered
//   u_target_border    paraboloid target border B in texels
//   u_view_rotation    world-from-view rotation of the sphere map's camera
//   u_samples          k: the texel is the mean of k x k samples at the centres
//                      of a k x k grid of sub-texels (1: one sample at the centre)

#define ENVMAP_LATLONG 0
#define ENVMAP_CUBE 1
#define ENVMAP_PARABOLOID 2
#define ENVMAP_SPHEREMAP 3

#if defined VERTEX_SHADER

#include "common/fullscreen_vs.glsl"

#elif defined FRAGMENT_SHADER

#include "common/latlong.glsl"
#include "common/cubemap.glsl"
#include "common/paraboloid.glsl"
#include "common/spheremap.glsl"

#if SOURCE == ENVMAP_CUBE
uniform samplerCube u_source;
#elif SOURCE == ENVMAP_PARABOLOID
uniform sampler2DArray u_source;
#else
uniform sampler2D u_source;
#endif
uniform float u_source_lod;
uniform float u_source_border;
uniform vec2 u_target_size;
uniform int u_target_face;
uniform float u_target_border;
uniform mat3 u_view_rotation;
uniform int u_samples;

out vec4 frag_color;

// World-space direction of target texture coordinates uv.
vec3 target_direction(vec2 uv) {
#if TARGET == ENVMAP_LATLONG
    return latlong_direction(uv);
#elif TARGET == ENVMAP_CUBE
    return cube_face_direction(u_target_face, uv);
#elif TARGET == ENVMAP_PARABOLOID
    return paraboloid_direction(u_target_face, uv, u_target_size.x, u_target_border);
#elif TARGET == ENVMAP_SPHEREMAP
    return u_view_rotation * spheremap_direction(uv);
#endif
}

// Source value in world-space direction d.
vec3 source_value(vec3 d) {
#if SOURCE == ENVMAP_LATLONG
    return textureLod(u_source, latlong_uv(d), u_source_lod).rgb;
#elif SOURCE == ENVMAP_CUBE
    return textureLod(u_source, d, u_source_lod).rgb;
#elif SOURCE == ENVMAP_PARABOLOID
    return paraboloid_texture_lod(u_source, d, u_source_border, u_source_lod).rgb;
#elif SOURCE == ENVMAP_SPHEREMAP
    return textureLod(u_source, spheremap_uv(transpose(u_view_rotation) * d), u_source_lod).rgb;
#endif
}

void main() {
    vec2 texel = floor(gl_FragCoord.xy);
    vec3 sum = vec3(0.0);
    for (int j = 0; j < u_samples; ++j) {
        for (int i = 0; i < u_samples; ++i) {
            vec2 offset = (vec2(i, j) + 0.5) / float(u_samples);
            sum += source_value(target_direction((texel + offset) / u_target_size));
        }
    }
    frag_color = vec4(sum / float(u_samples * u_samples), 1.0);
}

#endif
