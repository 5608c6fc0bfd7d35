#version 330 core
// Method `banks`, view = slice: one slice of the 3D map as the frame (seed 004
// Figure 6, right): the front paraboloid face of tangents t (border included, s to
// the right, t upwards) at w = angle(v, t) / 180 degrees; outside the unit disc
// the border's directions past the rim.
#if defined VERTEX_SHADER
#include "common/fullscreen_vs.glsl"
#elif defined FRAGMENT_SHADER
#include "common/paraboloid.glsl"
#include "banks/lookup.glsl"
uniform sampler3D u_map;
uniform float u_w;
uniform bool u_normalise;
in vec2 v_uv;
out vec4 f_color;

void main() {
    f_color = vec4(banks_glossy(u_map, vec3(v_uv, u_w), u_normalise), 1.0);
}
#endif
