#version 430 core
// Method `banks`, pass 2 of the 3D map (methods/banks/maps.py): every slice j of
// L_banks(t, cos theta_v) (seed 004 section 5.3) as the weighted sum of the ring
// table of pass 1 (rings.glsl),
//   rgb = sum_k w_k(theta_v,j) R_t(theta_k),   a = 2 pi sum_k w_k(theta_v,j),
// the weights of methods/banks/lobe.py ring_weights (texel (k, j) of u_weights); a is
// the map of a unit environment, by which the renderer may normalise the lobe.
#if defined COMPUTE_SHADER
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(rgba32f, binding = 0) uniform readonly image3D u_rings;
layout(rgba32f, binding = 1) uniform writeonly image3D u_map;
uniform sampler2D u_weights;

const float PI = 3.14159265358979;

void main() {
    ivec3 size = imageSize(u_map);
    ivec3 id = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(id, size))) return;
    int bins = imageSize(u_rings).z;
    vec3 sum = vec3(0.0);
    float unit = 0.0;
    for (int k = 0; k < bins; ++k) {
        float w = texelFetch(u_weights, ivec2(k, id.z), 0).r;
        if (w == 0.0) continue;
        sum += w * imageLoad(u_rings, ivec3(id.xy, k)).rgb;
        unit += w;
    }
    imageStore(u_map, id, vec4(sum, 2.0 * PI * unit));
}
#endif
