#version 330 core
// Method `mirror`: Blinn-Newell mirror reflection from the environment cube map
// (hardware trilinear filtering, no bias),
// combined with a diffuse term by seed 000 eq. 8,
//   L_o = (1 - F(r.n)) k_d E(n)/pi + F(r.n) L_mirror(r),
// with Schlick's F (seed 000 section 5.2) and E(n) from SH plus cap lights, as
// `kautz` has it (common/sh_irradiance.glsl), per fragment.
// Defines: SH_COEFFICIENTS (9, 25, 49), LIGHTS (0 .. 32).
#if defined VERTEX_SHADER
#include "common/mesh_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/fresnel.glsl"
#include "common/eq8.glsl"
#include "common/sh_irradiance.glsl"
uniform samplerCube u_environment;
out vec4 f_color;

void main() {
    const float PI = 3.14159265358979;
    vec3 n, r;
    reflection_frame(v_world_normal, v_world_position, u_camera_position, n, r);
    vec3 mirror = texture(u_environment, r).rgb;
    f_color = vec4(eq8_shade(n, r, sh_irradiance_if(u_kd, n) / PI, mirror, u_kd, u_fresnel), 1.0);
}
#endif
