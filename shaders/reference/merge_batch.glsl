#version 430 core
// Method `reference`, merge pass: one finished batch (accumulate.glsl's sum of
// estimates and their count per pixel) becomes its mean, which is added, with
// its square, to the accumulation. Every batch mean weighs 1, whatever its size
// (methods/sample_allocation.py); the squares give each pixel's standard error.
#if defined COMPUTE_SHADER
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform readonly image2D u_batch;
layout(rgba32f, binding = 1) uniform image2D u_sum;
layout(rgba32f, binding = 2) uniform image2D u_sum_sq;

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, imageSize(u_sum)))) return;
    vec4 batch = imageLoad(u_batch, pixel);
    if (batch.a == 0.0) return;
    vec3 mean = batch.rgb / batch.a;
    imageStore(u_sum, pixel, imageLoad(u_sum, pixel) + vec4(mean, 1.0));
    imageStore(u_sum_sq, pixel, imageLoad(u_sum_sq, pixel) + vec4(mean * mean, 1.0));
}
#endif
