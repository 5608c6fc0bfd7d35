#version 330 core
// Method `reference`, resolve pass: draws the reflectors (depth-tested against
// the frame's local objects) with the accumulated mean sum / count. During the
// window's first batch (u_first_pass) a pixel no batch has finished shows a preview
// (never merged into the estimate): where the running batch's band has passed, the
// sample-weighted mean of its 3x3 pixels, else the coarse first pass (a few samples per
// pixel at 1/u_preview_scale of the size) averaged over its neighbourhood.
#if defined VERTEX_SHADER
#include "common/mesh_vs.glsl"
#elif defined FRAGMENT_SHADER
uniform sampler2D u_sum;
uniform bool u_first_pass;
uniform sampler2D u_batch;
uniform sampler2D u_preview;
uniform int u_preview_scale;
out vec4 f_color;

// The coarse pass around `pixel`: the sample-weighted mean of the texels within a growing
// square (3x3 first), so a single weak draw does not show as black.
vec3 coarse(ivec2 pixel) {
    ivec2 centre = pixel / u_preview_scale;
    ivec2 size = textureSize(u_preview, 0);
    for (int radius = 1; radius <= 3; ++radius) {
        vec4 total = vec4(0.0);
        for (int dy = -radius; dy <= radius; ++dy) {
            for (int dx = -radius; dx <= radius; ++dx) {
                total += texelFetch(u_preview, clamp(centre + ivec2(dx, dy), ivec2(0), size - 1), 0);
            }
        }
        if (total.a > 0.0 && any(greaterThan(total.rgb, vec3(0.0)))) return total.rgb / total.a;
    }
    return vec3(0.0);
}

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    vec4 sum = texelFetch(u_sum, pixel, 0);
    if (sum.a > 0.0) {
        f_color = vec4(sum.rgb / sum.a, 1.0);
    } else if (u_first_pass) {
        vec4 batch = vec4(0.0);
        if (texelFetch(u_batch, pixel, 0).a > 0.0) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    batch += texelFetch(u_batch, pixel + ivec2(dx, dy), 0);
                }
            }
        }
        bool drawn = batch.a > 0.0 && any(greaterThan(batch.rgb, vec3(0.0)));
        f_color = vec4(drawn ? batch.rgb / batch.a : coarse(pixel), 1.0);
    } else {
        f_color = vec4(0.0, 0.0, 0.0, 1.0);
    }
}
#endif
