#version 430 core
// Method `banks`, pass 1 of the 3D map (methods/banks/maps.py, seed 004 section 5.3
// in the ring form of methods/banks/lobe.py): the environment integrated around rings
// about every tangent texel t of the front paraboloid face (border included),
//   R_t(theta_k) = 2 pi / M sum_m L(cos theta_k t + sin theta_k (cos phi_m e1 + sin phi_m e2)),
// theta_k = (k + 1/2) pi / K, phi_m = (m + 1/2) 2 pi / M, read from the static
// environment's cube map at the box mip level u_lod whose texels are about one
// bin wide. One invocation per (s texel, t texel, bin).
#if defined COMPUTE_SHADER
#include "common/paraboloid.glsl"
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(rgba32f, binding = 0) uniform writeonly image3D u_rings;
uniform samplerCube u_environment;
uniform float u_lod;
uniform float u_border;
uniform int u_ring_samples;

const float PI = 3.14159265358979;

// Duff et al. 2017: e1, e2 completing unit t (methods/banks/lobe.py orthonormal_basis).
void basis(vec3 t, out vec3 e1, out vec3 e2) {
    float sign_z = t.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sign_z + t.z);
    float b = t.x * t.y * a;
    e1 = vec3(1.0 + sign_z * t.x * t.x * a, sign_z * b, -sign_z * t.x);
    e2 = vec3(b, sign_z + t.y * t.y * a, -t.y);
}

void main() {
    ivec3 size = imageSize(u_rings);
    ivec3 id = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(id, size))) return;
    vec2 uv = (vec2(id.xy) + 0.5) / vec2(size.xy);
    vec3 t = paraboloid_direction(0, uv, float(size.x), u_border);
    vec3 e1, e2;
    basis(t, e1, e2);
    float theta = (float(id.z) + 0.5) * PI / float(size.z);
    vec3 axial = cos(theta) * t;
    float radius = sin(theta);
    vec3 sum = vec3(0.0);
    for (int m = 0; m < u_ring_samples; ++m) {
        float phi = (float(m) + 0.5) * 2.0 * PI / float(u_ring_samples);
        vec3 l = axial + radius * (cos(phi) * e1 + sin(phi) * e2);
        sum += textureLod(u_environment, l, u_lod).rgb;
    }
    imageStore(u_rings, id, vec4(sum * (2.0 * PI / float(u_ring_samples)), 1.0));
}
#endif
