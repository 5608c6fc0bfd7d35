#version 330 core
// Split screen and error heat map (viewer "Compare" panel).
// Left of the divider: method A; right: method B (often the reference), both
// through the display path (exposure, tone map, sRGB). With the heat map on,
// the left side shows instead the relative error |A - B| / max(B, eps) of
// luminance, mapped to colour over [0, u_heat_scale] (magma-like ramp).
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/tonemap.glsl"
#include "common/colormap.glsl"
uniform sampler2D u_hdr_a;
uniform sampler2D u_hdr_b;
uniform float u_exposure;
uniform int u_tonemap;
uniform float u_divider;      // x of the divider in framebuffer pixels
uniform bool u_split;
uniform bool u_heat;
uniform float u_heat_scale;   // relative error shown as the top of the colour scale
in vec2 v_uv;
out vec4 f_color;

vec3 display(vec3 radiance) {
    return srgb_encode(tonemap(radiance * exp2(u_exposure), u_tonemap));
}

void main() {
    vec3 a = texture(u_hdr_a, v_uv).rgb;
    vec3 b = texture(u_hdr_b, v_uv).rgb;
    float x = gl_FragCoord.x;
    if (u_split && abs(x - u_divider) < 1.0) {
        f_color = vec4(1.0);
        return;
    }
    bool right = u_split && x > u_divider;
    if (right) {
        f_color = vec4(display(b), 1.0);
    } else if (u_heat) {
        const vec3 luma = vec3(0.2126, 0.7152, 0.0722);
        float reference = dot(b, luma);
        float error = abs(dot(a, luma) - reference) / max(reference, 1e-3);
        f_color = vec4(colormap_magma(clamp(error / u_heat_scale, 0.0, 1.0)), 1.0);
    } else {
        f_color = vec4(display(a), 1.0);
    }
}
#endif
