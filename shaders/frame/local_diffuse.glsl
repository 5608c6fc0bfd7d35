#version 330 core
// Local diffuse objects (room walls, coloured boxes) as the frame draws them.
#if defined VERTEX_SHADER
#include "common/mesh_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/local_diffuse_fs.glsl"
#endif
