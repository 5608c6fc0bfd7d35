#version 330 core
// The reflectors' surface at each pixel, for the exact references (measure/exact_reference.py):
// u_output 0 writes the shading normal turned to the side of the face the camera sees
// (two-sided, as the reference's footprint.glsl / accumulate.glsl turn it), 1 the unit
// direction to the camera; 0 where no reflector is the nearest surface (local objects are
// drawn with u_value 0, depth and zero only, so they hide what they cover).
#if defined VERTEX_SHADER
#include "common/mesh_vs.glsl"
#elif defined FRAGMENT_SHADER
in vec3 v_world_position;
in vec3 v_world_normal;
uniform float u_value;
uniform int u_output;
uniform vec3 u_camera_position;
out vec4 f_color;

void main() {
    vec3 n = normalize(v_world_normal);
    if (!gl_FrontFacing) n = -n;
    vec3 v = normalize(u_camera_position - v_world_position);
    f_color = vec4(u_value * (u_output == 0 ? n : v), 1.0);
}
#endif
