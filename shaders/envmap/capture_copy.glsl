#version 430
// Dynamic cube capture (envmap/dynamic_cube.py): copies the 6n x n strip into
// level 0 of the cube map, face f from columns [f n, (f + 1) n), row for row
// (strip row 0 is the face's row 0, t = 0).
#if defined COMPUTE_SHADER
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) writeonly uniform imageCube u_target;
uniform sampler2D u_strip;
uniform int u_size;  // n

void main() {
    ivec3 id = ivec3(gl_GlobalInvocationID);
    if (id.x >= u_size || id.y >= u_size) {
        return;
    }
    imageStore(u_target, id, texelFetch(u_strip, ivec2(id.z * u_size + id.x, id.y), 0));
}
#endif
