#version 430
// One level of the cross-face ("seamless") mip chain of method `kautz`, past seed 000
// section 6 (Figure 4, the border problem): the hardware box filter averages the 2 x 2
// children inside one face, so at high levels the six faces hold six unrelated
// averages and their borders show. Here texel (j, i) of level k (m x m per face)
// averages the 4 x 4 texels of level k - 1 around it (its 2 x 2 children and the ring
// beyond), each weighted by its solid angle (1 + a^2 + b^2)^(-3/2) and by a tent in
// the *angle* to the texel's centre direction, of radius two source texel spacings
// (on a uniform grid that is the [1 3 3 1] x [1 3 3 1] kernel; measured in angle it
// stays centred on the texel near edges and at the coarse levels, where the face
// plane squeezes the angles). Texels beyond an edge come from the neighbouring face,
// unfolded into the plane of this one: with the face frame d = F + a R + b U, a
// point at a > 1 lies at distance a - 1 from the edge on the face whose forward axis
// is R, i.e. d = R + (2 - a) F + b U (and alike for a < -1 and for b; corner samples
// unfold twice), so adjacent texels across an edge average overlapping regions, as
// adjacent texels inside a face do.
// envmap/mipmaps.py dispatches it once per level with a barrier in between.
#if defined COMPUTE_SHADER
#include "common/cubemap.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) writeonly uniform imageCube u_target;  // level k
uniform samplerCube u_source;  // the same texture, LINEAR_MIPMAP_NEAREST
uniform int u_level;           // k >= 1
uniform int u_size;            // m, the face size at level k

// Direction of face-plane point (a, b) of the face with frame (F, R, U), unfolded onto
// the neighbouring faces when |a| or |b| exceeds 1; `density` gets the solid-angle
// density (1 + a'^2 + b'^2)^(-3/2) at the unfolded point (a', b').
vec3 unfolded_direction(vec3 F, vec3 R, vec3 U, vec2 ab, out float density) {
    if (ab.x > 1.0) {
        vec3 f = R;
        R = -F;
        F = f;
        ab.x -= 2.0;
    } else if (ab.x < -1.0) {
        vec3 f = -R;
        R = F;
        F = f;
        ab.x += 2.0;
    }
    if (ab.y > 1.0) {
        vec3 f = U;
        U = -F;
        F = f;
        ab.y -= 2.0;
    } else if (ab.y < -1.0) {
        vec3 f = -U;
        U = F;
        F = f;
        ab.y += 2.0;
    }
    density = pow(1.0 + dot(ab, ab), -1.5);
    return F + ab.x * R + ab.y * U;
}

void main() {
    ivec3 id = ivec3(gl_GlobalInvocationID);
    if (id.x >= u_size || id.y >= u_size) {
        return;
    }
    // The face frame: d(a, b) = F + a R + b U with (a, b) = 2 (s, t) - 1.
    vec3 F = cube_face_direction(id.z, vec2(0.5));
    vec3 R = cube_face_direction(id.z, vec2(1.0, 0.5)) * sqrt(2.0) - F;
    vec3 U = cube_face_direction(id.z, vec2(0.5, 1.0)) * sqrt(2.0) - F;
    vec3 centre = normalize(F + ((vec2(id.xy) + 0.5) / float(u_size) * 2.0 - 1.0).x * R
                            + ((vec2(id.xy) + 0.5) / float(u_size) * 2.0 - 1.0).y * U);
    vec3 d[16];
    float density[16];
    for (int q = 0; q < 16; ++q) {
        // Centres of source texels 2j - 1 .. 2j + 2 (and rows alike), in face coordinates.
        vec2 uv = (vec2(2 * id.xy + ivec2(q % 4, q / 4)) - 0.5) / float(2 * u_size);
        d[q] = normalize(unfolded_direction(F, R, U, 2.0 * uv - 1.0, density[q]));
    }
    // Tent radius: two source texel spacings, measured as angles at this texel.
    float radius = acos(clamp(dot(d[5], d[6]), -1.0, 1.0)) + acos(clamp(dot(d[5], d[9]), -1.0, 1.0));
    vec3 sum = vec3(0.0);
    float total = 0.0;
    for (int q = 0; q < 16; ++q) {
        float angle = acos(clamp(dot(centre, d[q]), -1.0, 1.0));
        float w = max(1.0 - angle / radius, 0.0) * density[q];
        sum += w * textureLod(u_source, d[q], float(u_level - 1)).rgb;
        total += w;
    }
    imageStore(u_target, id, vec4(sum / total, 1.0));
}
#endif
