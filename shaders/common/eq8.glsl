// Shading of a reflector fragment shared by `mirror`, `hwconv`, `banks` and `rsibr`: the frame and
// seed 000 eq. 8 (seed 004 eq. 2 with F_d = 1 - F, F_p = F),
//   L_o = (1 - F(r.n)) k_d L_diffuse + F(r.n) L_glossy(r),
// with Schlick's F (seed 000 section 5.2). Each method brings its own L_diffuse,
// E(n)/pi by its paper's means: SH irradiance (`mirror`, common/sh_irradiance.glsl),
// Miller's diffuse map (`hwconv`, `banks`, shading/miller_map.py) or Lambertian radiance
// maps (`rsibr`). Include after common/fresnel.glsl in a FRAGMENT_SHADER section whose
// vertex stage writes the world-space varyings (common/mesh_world.glsl).

uniform vec3 u_camera_position;
uniform vec3 u_fresnel;  // f_lambda per RGB channel
uniform vec3 u_kd;
in vec3 v_world_position;
in vec3 v_world_normal;

#include "common/reflection.glsl"

// Eq. 8 from the diffuse radiance E(n)/pi of a white surface and the glossy radiance along r.
// F, k_d and f0 per RGB channel.
vec3 eq8_shade(vec3 n, vec3 r, vec3 diffuse, vec3 glossy, vec3 kd, vec3 f0) {
    return mix(kd * diffuse, glossy, schlick_fresnel(f0, dot(r, n)));
}
