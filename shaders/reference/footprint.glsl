// The surface under a point of the pixel's footprint, found by tracing the
// camera ray through it (reference/trace.glsl): the anti-aliased image is the
// box-filtered mean over the part of the footprint the reflectors cover, so a
// footprint point that misses them, or meets a local object first, is no
// sample of this pixel. The rasterised surface at the pixel centre cannot
// stand in for it: extrapolated across the footprint (interpolateAtOffset)
// its plane leaves the mesh near silhouettes, where rays from it hit the
// reflector itself (traced diffuse spheres came out 43 % too dark, issue 13).
uniform mat4 u_inverse_view_projection;
uniform vec2 u_viewport;

// Surface point p, shading normal n and face normal g under window position
// `window` (pixels).
bool footprint_surface(vec2 window, vec3 camera, out vec3 p, out vec3 n, out vec3 g) {
    vec4 far = u_inverse_view_projection * vec4(2.0 * window / u_viewport - 1.0, 1.0, 1.0);
    vec3 direction = normalize(far.xyz / far.w - camera);
    float t;
    int tri;
    vec2 uv;
    if (!trace_closest(camera, direction, t, tri, uv)) return false;
    if (trace_triangles[7 * tri + 6].a < 0.5) return false;
    p = camera + t * direction;
    n = hit_shading_normal(tri, uv);
    g = hit_face_normal(tri);
    return true;
}
