#version 330 core
// Method `hwconv`, view = S, L, blended or source: the chosen dual-paraboloid map as
// the frame, front face (z >= 0) on the left, back face on the right, each upright
// (t grows upwards), as envmap.conversions.save_paraboloid_exr lays them out.
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
uniform sampler2D u_front;
uniform sampler2D u_back;
in vec2 v_uv;
out vec4 f_color;

void main() {
    vec2 uv = vec2(fract(2.0 * v_uv.x), v_uv.y);
    vec3 front = textureLod(u_front, uv, 0.0).rgb;
    vec3 back = textureLod(u_back, uv, 0.0).rgb;
    f_color = vec4(v_uv.x < 0.5 ? front : back, 1.0);
}
#endif
