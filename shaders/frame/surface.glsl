#version 330 core
// The reflectors' surface at each pixel, for the exact references (measure/exact_reference.py):
// u_output 0 writes the shading normal turned to the side of the face the camera sees
// (two-sided, as the reference's footprint.glsl / accumulate.glsl turn it), 1 the unit
// direction to the camera, and with TANGENTS, 2 the unit tangent of the Banks material
// orthogonal to that normal (banks_brdf.glsl's banks_tangent, as accumulate.glsl takes it);
// 0 where no reflector is the nearest surface (local objects are drawn with u_value 0, depth
// and zero only, so they hide what they cover).
#if defined VERTEX_SHADER
// (the includes stay outside #if: the preprocessor includes a file once, wherever it is)
#include "common/mesh_world.glsl"
#include "common/mesh_tangent.glsl"
uniform mat4 u_view;
uniform mat4 u_projection;

void main() {
    gl_Position = u_projection * u_view * mesh_world();
#if TANGENTS
    mesh_tangent();
#endif
}
#elif defined FRAGMENT_SHADER
#include "common/banks_brdf.glsl"
#if TANGENTS
in vec3 v_world_tangent;
#endif
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
    vec3 value = u_output == 0 ? n : v;
#if TANGENTS
    if (u_output == 2) value = banks_tangent(v_world_tangent, n);
#endif
    f_color = vec4(u_value * value, 1.0);
}
#endif
