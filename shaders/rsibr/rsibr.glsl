#version 330 core
// Method `rsibr` (seed 002 §4, RenderObject): the reflector sphere-mapped from the
// generated radiance map. The eye-space mirror direction r_eye is looked up as
// GL_SPHERE_MAP does, p = g_mirror^-1(r_eye) (§3.3; the texel of r is the texel
// of its normal, so the normal-warped maps are read the same way), in perspective
// as the paper does, accepting that the maps were made for one view direction
// (§2). What the map does not hold is added here: for Phong, Schlick Fresnel and
// the diffuse term by seed 000 eq. 8 (as `mirror`); for Lambertian, k_d; the car
// paint's maps hold everything.
#if defined VERTEX_SHADER
#include "common/mesh_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/fresnel.glsl"
#include "common/eq8.glsl"
uniform sampler2D u_map;
uniform samplerCube u_environment;
uniform mat4 u_view;
uniform int u_shading;       // 0 phong (eq. 8), 1 lambertian (k_d), 2 as baked
out vec4 f_color;

void main() {
    vec3 n, r;
    reflection_frame(v_world_normal, v_world_position, u_camera_position, n, r);
    vec3 r_eye = normalize(mat3(u_view) * r);
    float m = length(r_eye + vec3(0.0, 0.0, 1.0));
    vec2 uv = m > 0.0 ? 0.5 * r_eye.xy / m + 0.5 : vec2(0.5, 0.0);
    vec3 value = texture(u_map, uv).rgb;
    vec3 color = value;
    if (u_shading == 0) {
        color = eq8_shade(u_environment, n, r, value, u_kd, u_diffuse_level, u_fresnel);
    } else if (u_shading == 1) {
        color = u_kd * value;
    }
    f_color = vec4(color, 1.0);
}
#endif
