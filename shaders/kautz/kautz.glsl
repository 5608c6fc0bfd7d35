#version 330 core
// Method `kautz` (seed 000): diffuse and glossy environment reflections in one pass.
//   diffuse  (section 4.1)  E(n) from SH (eq. 12), optionally plus cap lights
//                           (common/sh_irradiance.glsl); L_diffuse = k_d / pi * E(n)
//   glossy   (section 4.2)  the cube map's box-filtered mip chain looked up with the
//                           reflection vector and LOD bias b: texture(cube, r, b)
//   Fresnel  (section 5.2)  Schlick with the single parameter f_lambda, per RGB channel
//   combined (eq. 8)        L_o = (1 - F) L_diffuse + F L_glossy
// Without PER_PIXEL the diffuse term and F are evaluated per vertex (as the paper
// does) and interpolated; with it, per fragment. The reflection vector of the glossy
// lookup is per fragment either way, so b = 0 is exactly method `mirror`.
// With LOD_LEVEL, b is an absolute mip level instead of a bias added to the hardware's
// screen-space LOD (so the blur no longer depends on the image resolution and the
// object's size on screen), clamped below by an estimate of that LOD.
// Defines: PER_PIXEL (0/1), LOD_LEVEL (0/1), SH_COEFFICIENTS (9, 25, 49), LIGHTS (0 .. 32).
#include "common/fresnel.glsl"
#include "common/sh_irradiance.glsl"
uniform vec3 u_camera_position;
uniform vec3 u_fresnel;

#if defined VERTEX_SHADER
#include "common/mesh_world.glsl"
uniform mat4 u_view;
uniform mat4 u_projection;
#if !PER_PIXEL
out vec3 v_irradiance;
out vec3 v_fresnel;
#endif

void main() {
    vec4 world = mesh_world();
    gl_Position = u_projection * u_view * world;
#if !PER_PIXEL
    vec3 n = normalize(v_world_normal);
    vec3 v = normalize(u_camera_position - world.xyz);
    if (dot(n, v) < 0.0) {
        n = -n;  // back faces of open meshes (the teapot) reflect too
    }
    v_irradiance = sh_irradiance(n);
    v_fresnel = schlick_fresnel(u_fresnel, dot(reflect(-v, n), n));
#endif
}

#elif defined FRAGMENT_SHADER
uniform samplerCube u_environment;
uniform float u_lod_bias;
uniform vec3 u_kd;
in vec3 v_world_position;
in vec3 v_world_normal;
#if !PER_PIXEL
in vec3 v_irradiance;
in vec3 v_fresnel;
#endif
out vec4 f_color;

void main() {
    const float PI = 3.14159265358979;
    vec3 n = normalize(v_world_normal);
    vec3 v = normalize(u_camera_position - v_world_position);
    if (dot(n, v) < 0.0) {
        n = -n;
    }
    vec3 r = reflect(-v, n);
#if LOD_LEVEL
    // The footprint of a pixel: the angle r turns through per pixel, in face texels of
    // about 2 / n radians (exact at a face's centre, 1/3 level finer at its corners).
    vec3 rn = normalize(r);
    float turn = max(length(dFdx(rn)), length(dFdy(rn)));
    float footprint = log2(max(turn * float(textureSize(u_environment, 0).x) * 0.5, 1e-6));
    vec3 glossy = textureLod(u_environment, r, max(u_lod_bias, footprint)).rgb;
#else
    vec3 glossy = texture(u_environment, r, u_lod_bias).rgb;
#endif
#if PER_PIXEL
    vec3 irradiance = sh_irradiance(n);
    vec3 F = schlick_fresnel(u_fresnel, dot(r, n));
#else
    vec3 irradiance = v_irradiance;
    vec3 F = v_fresnel;
#endif
    f_color = vec4(mix(u_kd / PI * irradiance, glossy, F), 1.0);
}
#endif
