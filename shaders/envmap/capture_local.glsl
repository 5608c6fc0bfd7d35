#version 330 core
// Dynamic cube capture (envmap/dynamic_cube.py), the local objects: one
// instanced draw covers all six faces of the 6n x n strip. Instance f is seen
// by face camera f (90 degrees, u_face_views[f]); its clip x is squeezed into
// the strip's sixth for face f, x' = (x + (2f + 1) w) / 6 - w, and the two clip
// distances w + x >= 0 and w - x >= 0 cut it at the face's side edges, as the
// viewport would for a face rendered alone (seed 000 section 5.1 renders the
// six faces in six passes; here the GPU does them in one).
#if defined VERTEX_SHADER
#include "common/mesh_world.glsl"
uniform mat4 u_face_views[6];
uniform mat4 u_projection;

void main() {
    vec4 world = mesh_world();
    vec4 clip = u_projection * u_face_views[gl_InstanceID] * world;
    gl_ClipDistance[0] = clip.w + clip.x;
    gl_ClipDistance[1] = clip.w - clip.x;
    clip.x = (clip.x + float(2 * gl_InstanceID + 1) * clip.w) / 6.0 - clip.w;
    gl_Position = clip;
}
#elif defined FRAGMENT_SHADER
#include "common/local_diffuse_fs.glsl"
#endif
