#version 330 core
// Method `rsibr` (seed 002 §4, RenderObject): the reflector sphere-mapped from the
// generated radiance map. The eye-space mirror direction r_eye is looked up as
// GL_SPHERE_MAP does, p = g_mirror^-1(r_eye) (§3.3; the texel of r is the texel
// of its normal, so the normal-warped maps are read the same way), in perspective
// as the paper does, accepting that the maps were made for one view direction
// (§2). What the map does not hold is added here: for Phong, Schlick Fresnel and
// the diffuse term by seed 000 eq. 8, the diffuse radiance E(n)/pi read from the
// normal-warped Lambertian map at the same texel (u_diffuse_map, §3); for
// Lambertian, k_d; the car paint's maps hold everything.
#if defined VERTEX_SHADER
#include "common/mesh_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/fresnel.glsl"
#include "common/eq8.glsl"
uniform sampler2D u_map;
uniform sampler2D u_diffuse_map;
uniform bool u_has_diffuse_map;  // false while the window's first Lambertian bake runs
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
        // the normal-warped map is indexed by the eye-space normal itself (g_normal^-1,
        // §3.3): exact in perspective too, where the texel of r is not quite that of n
        vec2 uv_n = 0.5 * normalize(mat3(u_view) * n).xy + 0.5;
        vec3 diffuse = u_has_diffuse_map ? texture(u_diffuse_map, uv_n).rgb : vec3(0.0);
        color = eq8_shade(n, r, diffuse, value, u_kd, u_fresnel);
    } else if (u_shading == 1) {
        color = u_kd * value;
    }
    f_color = vec4(color, 1.0);
}
#endif
