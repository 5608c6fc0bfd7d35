#version 330 core
// Method `mirror`: Blinn-Newell mirror reflection from the environment cube map
// (hardware trilinear filtering, no bias),
// combined with a diffuse term by seed 000 eq. 8,
//   L_o = (1 - F(r.n)) L_diffuse + F(r.n) L_mirror,
// with Schlick's F (seed 000 section 5.2). The diffuse term is SH-free: k_d
// times the cube map's second-to-last mip level looked up along the normal, a
// 2x2-texel-per-face box average standing in for (1/pi) * irradiance.
#if defined VERTEX_SHADER
#include "common/mesh_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/fresnel.glsl"
#include "common/eq8.glsl"
uniform samplerCube u_environment;
out vec4 f_color;

void main() {
    vec3 n, r;
    reflection_frame(v_world_normal, v_world_position, u_camera_position, n, r);
    vec3 mirror = texture(u_environment, r).rgb;
    f_color = vec4(eq8_shade(u_environment, n, r, mirror, u_kd, u_diffuse_level, u_fresnel), 1.0);
}
#endif
