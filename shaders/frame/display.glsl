#version 330 core
// HDR target -> screen: exposure (stops), tone map, sRGB encode.
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/tonemap.glsl"
uniform sampler2D u_hdr;
uniform float u_exposure;
uniform int u_tonemap;
in vec2 v_uv;
out vec4 f_color;

void main() {
    vec3 radiance = texture(u_hdr, v_uv).rgb * exp2(u_exposure);
    f_color = vec4(srgb_encode(tonemap(radiance, u_tonemap)), 1.0);
}
#endif
