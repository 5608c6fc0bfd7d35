// Standard mesh vertex stage: world position and normal for per-pixel shading.
// Include in a VERTEX_SHADER section; defines main().
#include "common/mesh_world.glsl"
uniform mat4 u_view;
uniform mat4 u_projection;

void main() {
    gl_Position = u_projection * u_view * mesh_world();
}
