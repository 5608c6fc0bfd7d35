// Ray tracing of the scene's triangles for the reference: closest hits
// through a BVH (paths.glsl follows them: self-occlusion, local and
// self-reflections; footprint.glsl finds the surface under the pixel). BVH layout of app/envstudio/core/bvh.py,
// uploaded by app/envstudio/methods/tracing.py into two shader storage buffers
// of vec4 (OpenGL 4.3; plain loads, where texelFetch went through the sampler):
//   nodes:     2 vec4 per node: (min.xyz, right child or first triangle),
//              (max.xyz, triangle count; 0 for interior nodes)
//   triangles: 7 vec4 per triangle: v0, v1, v2, n0, n1, n2, (albedo.rgb, kind)
//              kind 0 = local diffuse object, 1 = reflector

#define TRACE_EDGE_EPSILON 1e-5
// Traversal stack entries: methods/tracing.py sets the BVH's depth + 2, all the
// near-first traversal can hold. The stack lives in per-ray local memory, so it
// is kept as small as the scene allows: on the H100 a fixed 48 entries cost 25 %
// of the reference's time against 16.
#ifndef TRACE_STACK
#define TRACE_STACK 48
#endif

layout(std430, binding = 0) readonly buffer TraceNodes { vec4 trace_nodes[]; };
layout(std430, binding = 1) readonly buffer TraceTriangles { vec4 trace_triangles[]; };

// Moller-Trumbore; returns t > 0 or -1, barycentrics in uv.
float ray_triangle(vec3 o, vec3 d, vec3 a, vec3 b, vec3 c, out vec2 uv) {
    vec3 e1 = b - a;
    vec3 e2 = c - a;
    vec3 p = cross(d, e2);
    float det = dot(e1, p);
    if (abs(det) < 1e-12) return -1.0;
    float inv = 1.0 / det;
    vec3 s = o - a;
    uv.x = dot(s, p) * inv;
    vec3 q = cross(s, e1);
    uv.y = dot(d, q) * inv;
    float t = dot(e2, q) * inv;
    // Triangles are widened by TRACE_EDGE_EPSILON (barycentric) so rays through a
    // shared edge cannot slip between two triangles in float arithmetic and leak
    // out of a closed room into the (bright) environment.
    if (uv.x < -TRACE_EDGE_EPSILON || uv.y < -TRACE_EDGE_EPSILON
        || uv.x + uv.y > 1.0 + TRACE_EDGE_EPSILON || t <= 1e-6) return -1.0;
    return t;
}

// Entry distance of the ray into node's box, or -1 where it misses or enters
// beyond t_max.
float trace_box_entry(int node, vec3 o, vec3 inv, float t_max) {
    vec3 t0 = (trace_nodes[2 * node].xyz - o) * inv;
    vec3 t1 = (trace_nodes[2 * node + 1].xyz - o) * inv;
    vec3 tmin = min(t0, t1);
    vec3 tmax = max(t0, t1);
    float near = max(max(tmin.x, tmin.y), max(tmin.z, 0.0));
    float far = min(min(tmax.x, tmax.y), min(tmax.z, t_max));
    return far < near ? -1.0 : near;
}

// Closest hit, children visited near first: both child boxes are tested at
// their parent and pushed with their entry distances, and an entry beyond the
// closest hit so far is skipped when popped.
bool trace_closest(vec3 o, vec3 d, out float t_hit, out int tri_hit, out vec2 bary) {
    vec3 inv = 1.0 / mix(d, vec3(1e-30), equal(d, vec3(0.0)));
    int stack[TRACE_STACK];
    float entry[TRACE_STACK];
    int top = 0;
    t_hit = 1e30;
    tri_hit = -1;
    if (trace_box_entry(0, o, inv, t_hit) >= 0.0) {
        stack[top] = 0;
        entry[top++] = 0.0;
    }
    while (top > 0) {
        --top;
        if (entry[top] > t_hit) continue;
        int node = stack[top];
        int link = int(trace_nodes[2 * node].w);
        int count = int(trace_nodes[2 * node + 1].w);
        if (count > 0) {
            for (int k = link; k < link + count; ++k) {
                vec2 uv;
                float t = ray_triangle(o, d, trace_triangles[7 * k].xyz,
                                       trace_triangles[7 * k + 1].xyz,
                                       trace_triangles[7 * k + 2].xyz, uv);
                if (t > 0.0 && t < t_hit) {
                    t_hit = t;
                    tri_hit = k;
                    bary = uv;
                }
            }
            continue;
        }
        float t_left = trace_box_entry(node + 1, o, inv, t_hit);
        float t_right = trace_box_entry(link, o, inv, t_hit);
        bool left_first = t_right < 0.0 || (t_left >= 0.0 && t_left <= t_right);
        int near_node = left_first ? node + 1 : link;
        int far_node = left_first ? link : node + 1;
        float t_near = left_first ? t_left : t_right;
        float t_far = left_first ? t_right : t_left;
        if (t_far >= 0.0 && top < TRACE_STACK) {
            stack[top] = far_node;
            entry[top++] = t_far;
        }
        if (t_near >= 0.0 && top < TRACE_STACK) {
            stack[top] = near_node;
            entry[top++] = t_near;
        }
    }
    return tri_hit >= 0;
}

// Unit face normal of triangle tri (its winding's orientation).
vec3 hit_face_normal(int tri) {
    vec3 a = trace_triangles[7 * tri].xyz;
    return normalize(cross(trace_triangles[7 * tri + 1].xyz - a,
                           trace_triangles[7 * tri + 2].xyz - a));
}

// Interpolated vertex normal at a hit, or the face normal where the vertex
// normals cancel (seams and tips of open meshes): a zero-length normal would
// make the bounce direction NaN, which misses everything and "sees" the sky.
vec3 hit_shading_normal(int tri, vec2 uv) {
    vec3 n = (1.0 - uv.x - uv.y) * trace_triangles[7 * tri + 3].xyz
             + uv.x * trace_triangles[7 * tri + 4].xyz
             + uv.y * trace_triangles[7 * tri + 5].xyz;
    return dot(n, n) > 1e-8 ? normalize(n) : hit_face_normal(tri);
}
