#version 430 core
// Method `reference`, merge pass of the control variate (untraced_too): the finished batch's
// traced mean minus its untraced mean, from the same samples, is added with its square to the
// difference's own sums, as merge_batch.glsl adds each mean. Its spread gives the standard
// error of traced − untraced, what is left to sample once the untraced model is known
// exactly (measure/compare.py: traced = exact untraced + mean of the differences).
#if defined COMPUTE_SHADER
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform readonly image2D u_batch;
layout(rgba32f, binding = 1) uniform image2D u_sum;
layout(rgba32f, binding = 2) uniform image2D u_sum_sq;
layout(rgba32f, binding = 3) uniform readonly image2D u_untraced_batch;

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, imageSize(u_sum)))) return;
    vec4 batch = imageLoad(u_batch, pixel);
    if (batch.a == 0.0) return;
    vec3 difference = (batch.rgb - imageLoad(u_untraced_batch, pixel).rgb) / batch.a;
    imageStore(u_sum, pixel, imageLoad(u_sum, pixel) + vec4(difference, 1.0));
    imageStore(u_sum_sq, pixel, imageLoad(u_sum_sq, pixel) + vec4(difference * difference, 1.0));
}
#endif
