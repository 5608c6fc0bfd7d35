#version 330 core
// Method `flat` (plugin example): the reflector in one colour under a fixed key light.
// "flat/shade.glsl" is the plugin's own file, "common/..." envmap-studio's.
#if defined VERTEX_SHADER
#include "common/mesh_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "flat/shade.glsl"
uniform vec3 u_colour;
uniform float u_ambient;
in vec3 v_world_position;
in vec3 v_world_normal;
out vec4 f_color;

void main() {
    f_color = vec4(flat_shade(u_colour, u_ambient, normalize(v_world_normal)), 1.0);
}
#endif
