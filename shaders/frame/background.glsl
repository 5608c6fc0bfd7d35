#version 330 core
// The environment at infinity behind the objects: each pixel looks up the
// cube map along its world-space view ray (level 0, no bias).
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
uniform samplerCube u_environment;
uniform mat4 u_inverse_view_projection;
in vec2 v_uv;
out vec4 f_color;

void main() {
    vec4 far_point = u_inverse_view_projection * vec4(v_uv * 2.0 - 1.0, 1.0, 1.0);
    vec4 near_point = u_inverse_view_projection * vec4(v_uv * 2.0 - 1.0, -1.0, 1.0);
    vec3 direction = normalize(far_point.xyz / far_point.w - near_point.xyz / near_point.w);
    f_color = vec4(textureLod(u_environment, direction, 0.0).rgb, 1.0);
}
#endif
