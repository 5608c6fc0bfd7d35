#version 330 core
// Method `hwconv`, seed 004 section 5.2 steps 13-14: the reflector with the
// prefiltered dual-paraboloid map looked up along the reflection vector r
// (the Phong environment map L_phong(r) of section 4), combined with a diffuse
// term by seed 004 eq. 2 with seed 000's Schlick weights (common/eq8.glsl),
//   L_o = (1 - F(r.n)) k_d L_diffuse(n) + F(r.n) L_phong(r),
// L_diffuse being Miller's diffuse map indexed by the normal (section 4,
// shading/miller_map.py).
#if defined VERTEX_SHADER
#include "common/mesh_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/fresnel.glsl"
#include "common/eq8.glsl"
#include "common/paraboloid.glsl"
uniform sampler2D u_front;
uniform sampler2D u_back;
uniform samplerCube u_diffuse_map;
uniform float u_size;
uniform float u_border;
out vec4 f_color;

void main() {
    vec3 n, r;
    reflection_frame(v_world_normal, v_world_position, u_camera_position, n, r);
    int face;
    vec2 uv = paraboloid_uv(r, u_size, u_border, face);
    vec3 front = textureLod(u_front, uv, 0.0).rgb;
    vec3 back = textureLod(u_back, uv, 0.0).rgb;
    vec3 glossy = face == 0 ? front : back;
    f_color = vec4(eq8_shade(n, r, texture(u_diffuse_map, n).rgb, glossy, u_kd, u_fresnel), 1.0);
}
#endif
