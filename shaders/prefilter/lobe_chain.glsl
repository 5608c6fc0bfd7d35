#version 330 core
// One face of one level of a prefiltered cube mip chain (app/envstudio/prefilter/chain_gpu.py):
// every fragment is one target texel of centre direction r, whose lobe about r is integrated
// by importance sampling with filtered importance sampling (Krivanek & Colbert 2008,
// "Real-time Shading with Filtered Importance Sampling", EGSR): each sample reads the
// source's mip chain at the level whose texels cover the sample's share of the sphere,
// 1 / (count pdf). Lobes: the normalised Phong lobe (N + 1) / 2pi max(<r, l>, 0)^N (seed
// 004 section 4, L_phong; chain_gpu.lobe_samples) and split-sum GGX (Karis 2013: l the
// reflection of r about GGX half vectors, weighted by <r, l>; chain_gpu.ggx_lobe_samples).
//
// The samples are the same for every texel (a Fibonacci lattice in the lobe's frame):
// u_table row 0, texel i = (x, y, z, lod) with z = cos(theta) about r and
// lod = 0.5 log2(omega_s) + bias, omega_s = 1 / (count pdf); row 1, texel i = (w, 0, 0, 0),
// the sample's weight, the weights summing to 1 (Phong: the pdf equals the kernel and every
// w is 1 / count; GGX: w proportional to <r, l>). Here the level-0 source
// texel's solid angle at l is taken off, 0.5 log2(omega_texel(l)):
//   SOURCE 0, cube of face n:  omega_texel = (2 / n)^2 |l_ma|^3 (l_ma: the major-axis
//                              component; texels shrink towards the face corners);
//   SOURCE 1, lat-long of h rows: (pi / h)^2, the square of a row's angle. The texel's
//                              true solid angle shrinks with sin(theta) towards the poles,
//                              but a mip level blurs rows and columns alike, and a level
//                              chosen by area there would blur 1 / sin(theta) times too far
//                              along the meridian.
//
// Defines: SOURCE (0 cube, 1 lat-long).
// Uniforms:
//   u_source      samplerCube (SOURCE 0) or sampler2D (SOURCE 1; REPEAT in s), RGBA32F /
//                 RGB32F with its mip chain (trilinear)
//   u_source_max  its coarsest mip level
//   u_texel_log2  0.5 log2 of omega_texel's constant factor: log2(2 / n) or log2(pi / h)
//   u_table       sampler2D (count x 2, RGBA32F) of the samples and weights above
//   u_count       number of samples
//   u_face        target face 0..5 (OpenGL order, shaders/common/cubemap.glsl)
//   u_size        target face edge in texels
//   u_split       f: the target is drawn f x f times larger, each fragment of a texel's
//                 f x f block summing every (f^2)-th sample from its index in the block, so
//                 small levels spread over the rasteriser's threads; the caller adds the
//                 blocks (every fragment writes its share of the texel's weighted sum)

#if defined VERTEX_SHADER

#include "common/fullscreen_vs.glsl"

#elif defined FRAGMENT_SHADER

#include "common/cubemap.glsl"
#include "common/latlong.glsl"

#if SOURCE == 0
uniform samplerCube u_source;
#else
uniform sampler2D u_source;
#endif
uniform float u_texel_log2;
uniform float u_source_max;
uniform sampler2D u_table;
uniform int u_count;
uniform int u_face;
uniform float u_size;
uniform int u_split;

out vec4 frag_color;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    ivec2 texel = pixel / u_split;
    ivec2 part = pixel - texel * u_split;
    vec3 r = cube_face_direction(u_face, (vec2(texel) + 0.5) / u_size);
    // Duff et al. 2017's branchless orthonormal basis about r.
    float sign_z = r.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sign_z + r.z);
    float b = r.x * r.y * a;
    vec3 t = vec3(1.0 + sign_z * r.x * r.x * a, sign_z * b, -sign_z * r.x);
    vec3 s = vec3(b, sign_z + r.y * r.y * a, -r.y);
    vec3 sum = vec3(0.0);
    for (int i = part.y * u_split + part.x; i < u_count; i += u_split * u_split) {
        vec4 q = texelFetch(u_table, ivec2(i, 0), 0);
        float w = texelFetch(u_table, ivec2(i, 1), 0).x;
        vec3 l = q.x * t + q.y * s + q.z * r;
#if SOURCE == 0
        vec3 m = abs(l);
        float lod = q.w - u_texel_log2 - 1.5 * log2(max(m.x, max(m.y, m.z)));
        sum += w * textureLod(u_source, l, clamp(lod, 0.0, u_source_max)).rgb;
#else
        float lod = q.w - u_texel_log2;
        sum += w * textureLod(u_source, latlong_uv(l), clamp(lod, 0.0, u_source_max)).rgb;
#endif
    }
    frag_color = vec4(sum, 1.0);
}

#endif
