// Shading of a reflector fragment shared by `mirror`, `hwconv`, `banks` and `rsibr`: the frame and
// seed 000 eq. 8,
//   L_o = (1 - F(r.n)) L_diffuse + F(r.n) L_glossy(r),
// with Schlick's F (seed 000 section 5.2) and the SH-free diffuse term: k_d times
// the cube map's mip level `diffuse_level` (2x2 texels per face) along n, standing
// in for (1/pi) * irradiance. Include after common/fresnel.glsl in a
// FRAGMENT_SHADER section whose vertex stage writes the world-space varyings
// (common/mesh_world.glsl).

uniform vec3 u_camera_position;
uniform float u_fresnel;
uniform float u_kd;
uniform float u_diffuse_level;
in vec3 v_world_position;
in vec3 v_world_normal;

#include "common/reflection.glsl"

// Eq. 8 with the glossy radiance looked up along r by the caller.
vec3 eq8_shade(samplerCube environment, vec3 n, vec3 r, vec3 glossy, float kd,
               float diffuse_level, float f0) {
    vec3 diffuse = kd * textureLod(environment, n, diffuse_level).rgb;
    return mix(diffuse, glossy, schlick_fresnel(f0, dot(r, n)));
}
