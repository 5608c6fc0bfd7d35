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
uniform samplerCube u_environment;
uniform vec3 u_camera_position;
uniform float u_fresnel;
uniform float u_kd;
uniform float u_diffuse_level;
in vec3 v_world_position;
in vec3 v_world_normal;
out vec4 f_color;

void main() {
    vec3 n = normalize(v_world_normal);
    vec3 v = normalize(u_camera_position - v_world_position);
    if (dot(n, v) < 0.0) {
        n = -n;  // back faces of open meshes (the teapot) reflect too
    }
    vec3 r = reflect(-v, n);
    vec3 mirror = texture(u_environment, r).rgb;
    vec3 diffuse = u_kd * textureLod(u_environment, n, u_diffuse_level).rgb;
    float F = schlick_fresnel(u_fresnel, dot(r, n));
    f_color = vec4(mix(diffuse, mirror, F), 1.0);
}
#endif
