#version 430 core
// Test probe: pixel i traces ray i (origins and directions from two RGB32F
// textures) through reference/trace.glsl and writes (t, triangle, 0, hit).
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/latlong.glsl"
uniform sampler2D u_latlong;
vec3 environment_radiance(vec3 l) { return vec3(0.0); }
#include "reference/trace.glsl"
uniform sampler2D u_origins;
uniform sampler2D u_directions;
out vec4 f_hit;

void main() {
    ivec2 texel = ivec2(gl_FragCoord.xy);
    vec3 o = texelFetch(u_origins, texel, 0).xyz;
    vec3 d = texelFetch(u_directions, texel, 0).xyz;
    float t;
    int tri;
    vec2 uv;
    bool hit = trace_closest(o, d, t, tri, uv);
    f_hit = vec4(hit ? t : -1.0, float(tri), 0.0, hit ? 1.0 : 0.0);
}
#endif
