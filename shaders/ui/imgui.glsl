#version 330 core
// Dear ImGui draw lists (envstudio.ui.imgui_renderer).
//
// in_position is in ImGui display coordinates: origin at the top-left of the
// display, y pointing down, in points (logical pixels). u_scale/u_offset map it
// to clip space with y flipped, so row 0 of the ImGui display lands on the top
// row of the framebuffer:
//   clip = in_position * u_scale + u_offset
//   u_scale  = (2 / W, -2 / H),  u_offset = (-1 - 2 L / W, 1 + 2 T / H)
// for a display rectangle (L, T, W, H). in_uv addresses textures whose row 0 was
// uploaded first (ImGui's top row at t = 0), so no v flip is needed. in_color is
// ImDrawVert.col, four unsigned bytes normalised to [0, 1], not linearised.

#if defined VERTEX_SHADER

uniform vec2 u_scale;
uniform vec2 u_offset;

in vec2 in_position;
in vec2 in_uv;
in vec4 in_color;

out vec2 v_uv;
out vec4 v_color;

void main() {
    v_uv = in_uv;
    v_color = in_color;
    gl_Position = vec4(in_position * u_scale + u_offset, 0.0, 1.0);
}

#elif defined FRAGMENT_SHADER

uniform sampler2D u_texture;

in vec2 v_uv;
in vec4 v_color;

out vec4 f_color;

void main() {
    f_color = v_color * texture(u_texture, v_uv);
}

#endif
