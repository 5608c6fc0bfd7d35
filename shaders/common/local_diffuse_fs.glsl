// Fragment stage of the local diffuse objects (room walls, coloured boxes):
// albedo/pi times the irradiance of the environment from its 9 SH coefficients
// (seed 000 eq. 12). Include in a FRAGMENT_SHADER section; defines main().
#include "common/sh.glsl"
uniform vec3 u_sh9[9];
uniform vec3 u_albedo;
in vec3 v_world_position;
in vec3 v_world_normal;
out vec4 f_color;

void main() {
    vec3 n = normalize(v_world_normal);
    vec3 irradiance = max(sh9_irradiance(u_sh9, n), vec3(0.0));
    f_color = vec4(u_albedo / 3.14159265358979 * irradiance, 1.0);
}
