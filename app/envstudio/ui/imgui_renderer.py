"""Draw Dear ImGui 1.92 frames with moderngl, including its dynamic textures.

moderngl-window 3.1.1's ``integrations.imgui_bundle`` renderer uploads the font
atlas once through ``ImFontAtlas.get_tex_data_as_rgba32``, which ImGui 1.92
removed (moderngl-window issue 222). Since 1.92 the renderer owns the texture
lifecycle instead: with ``BackendFlags_.renderer_has_textures`` set, every
``ImDrawData.textures`` entry carries a status the renderer must act on before
drawing::

    want_create   allocate a GPU texture, upload all pixels, store its id
    want_updates  upload the rectangles listed in ``updates`` (new glyphs)
    want_destroy  free the GPU texture once ``unused_frames > 0``

and draw commands name their texture by ``ImTextureRef``, resolved with
``ImDrawCmd.get_tex_id()``. The font atlas grows by creating a larger texture
and destroying the old one a frame later, so creations are rare; a steady UI
performs none (:attr:`ImGuiRenderer.texture_creations` counts them).

A texture id is the GL name (``moderngl.Texture.glo``) of the texture, for the
ones made here and for application textures given to
:meth:`ImGuiRenderer.register_texture`.

Each frame::

    imgui.render()
    renderer.render(imgui.get_draw_data())  # into the framebuffer bound now

Typical use in a moderngl-window ``WindowConfig`` (``ImGuiInput`` is in
:mod:`envstudio.ui.imgui_input`)::

    imgui.create_context()
    self.gui_input = ImGuiInput(imgui.get_io(), self.wnd.keys)
    self.gui = ImGuiRenderer(self.ctx)

    def on_render(self, time, frametime):
        self.gui_input.prepare_frame(self.wnd.size, self.wnd.buffer_size, frametime)
        imgui.new_frame()
        ...  # panels
        imgui.render()
        self.wnd.use()
        self.gui.render(imgui.get_draw_data())
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import moderngl
import numpy as np
from imgui_bundle import imgui

from envstudio.gpu.programs import ProgramLibrary

PROGRAM = "ui/imgui.glsl"

# OpenGL enums of the state this module reads back.
_GL_BLEND = 0x0BE2
_GL_CULL_FACE = 0x0B44
_GL_DEPTH_TEST = 0x0B71
_GL_SCISSOR_TEST = 0x0C11
_GL_SCISSOR_BOX = 0x0C10
_GL_VIEWPORT = 0x0BA2
_GL_BLEND_SRC_RGB = 0x80C9
_GL_BLEND_DST_RGB = 0x80C8
_GL_BLEND_SRC_ALPHA = 0x80CB
_GL_BLEND_DST_ALPHA = 0x80CA
_GL_BLEND_EQUATION_RGB = 0x8009
_GL_BLEND_EQUATION_ALPHA = 0x883D

# ImDrawVert: pos (2 float32), uv (2 float32), col (4 uint8, RGBA).
_VERTEX_FORMAT = "2f 2f 4f1"
_INDEX_DTYPE = {2: np.uint16, 4: np.uint32}
_COMPONENTS = {imgui.ImTextureFormat.rgba32: 4, imgui.ImTextureFormat.alpha8: 1}
_INITIAL_BUFFER_BYTES = 1 << 16


@dataclass(frozen=True)
class GLState:
    """The pipeline state :meth:`ImGuiRenderer.render` changes, as the driver reports it.

    Attributes
    ----------
    blend, depth_test, cull_face
        Whether ``GL_BLEND`` / ``GL_DEPTH_TEST`` / ``GL_CULL_FACE`` are enabled.
    scissor
        The scissor box ``(x, y, width, height)`` if ``GL_SCISSOR_TEST`` is
        enabled, else ``None`` (moderngl's ``ctx.scissor`` convention).
    viewport
        ``(x, y, width, height)`` in framebuffer pixels, origin bottom-left.
    blend_func
        GL enums ``(src_rgb, dst_rgb, src_alpha, dst_alpha)``.
    blend_equation
        GL enums ``(rgb, alpha)``.
    wireframe
        moderngl's polygon mode (core profiles cannot query it, so this one is
        moderngl's own record, ``ctx.wireframe``).
    """

    blend: bool
    depth_test: bool
    cull_face: bool
    scissor: tuple[int, int, int, int] | None
    viewport: tuple[int, int, int, int]
    blend_func: tuple[int, int, int, int]
    blend_equation: tuple[int, int]
    wireframe: bool

    def restore(self, ctx: moderngl.Context) -> None:
        """Set this state on ``ctx`` through moderngl, so its own records agree."""
        for flag, enabled in (
            (moderngl.BLEND, self.blend),
            (moderngl.DEPTH_TEST, self.depth_test),
            (moderngl.CULL_FACE, self.cull_face),
        ):
            if enabled:
                ctx.enable(flag)
            else:
                ctx.disable(flag)
        ctx.blend_func = self.blend_func
        ctx.blend_equation = self.blend_equation
        ctx.viewport = self.viewport
        ctx.scissor = self.scissor
        ctx.wireframe = self.wireframe


class GLStateQuery:
    """Reads :class:`GLState` from the driver (``glIsEnabled``, ``glGetIntegerv``).

    moderngl can set but not read enable flags and blend functions, so the two
    query functions are taken from the context's loader, ``ctx.mglo._context``:
    the object moderngl itself loads every GL function from (any context made by
    ``moderngl.create_context``, standalone or attached to a window).

    Parameters
    ----------
    ctx
        The context to query; it must be current when :meth:`capture` runs.
    """

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        loader = ctx.mglo._context
        self._is_enabled = ctypes.CFUNCTYPE(ctypes.c_ubyte, ctypes.c_uint)(
            loader.load_opengl_function("glIsEnabled")
        )
        self._get_integerv = ctypes.CFUNCTYPE(None, ctypes.c_uint, ctypes.POINTER(ctypes.c_int))(
            loader.load_opengl_function("glGetIntegerv")
        )

    def capture(self) -> GLState:
        """Return the current state of the context."""
        return GLState(
            blend=bool(self._is_enabled(_GL_BLEND)),
            depth_test=bool(self._is_enabled(_GL_DEPTH_TEST)),
            cull_face=bool(self._is_enabled(_GL_CULL_FACE)),
            scissor=(
                self._integers(_GL_SCISSOR_BOX, 4) if self._is_enabled(_GL_SCISSOR_TEST) else None
            ),
            viewport=self._integers(_GL_VIEWPORT, 4),
            blend_func=tuple(
                self._integers(pname, 1)[0]
                for pname in (
                    _GL_BLEND_SRC_RGB,
                    _GL_BLEND_DST_RGB,
                    _GL_BLEND_SRC_ALPHA,
                    _GL_BLEND_DST_ALPHA,
                )
            ),
            blend_equation=(
                self._integers(_GL_BLEND_EQUATION_RGB, 1)[0],
                self._integers(_GL_BLEND_EQUATION_ALPHA, 1)[0],
            ),
            wireframe=bool(self.ctx.wireframe),
        )

    def _integers(self, pname: int, count: int) -> tuple[int, ...]:
        values = (ctypes.c_int * count)()
        self._get_integerv(pname, values)
        return tuple(values)


class ImGuiRenderer:
    """Renders ``ImDrawData`` into the bound framebuffer and manages ImGui's textures.

    Construct it while the ImGui context it serves is current; it declares
    ``renderer_has_textures`` and ``renderer_has_vtx_offset`` on that context's
    IO and the GL texture size limit on its platform IO.

    Parameters
    ----------
    ctx
        The moderngl context to draw with (the window's, or a headless one).

    Attributes
    ----------
    texture_creations : int
        GPU textures created for ImGui so far (the font atlas: one at start,
        one more each time the atlas grows).
    texture_updates : int
        Partial uploads (``want_updates`` requests) performed so far.
    """

    def __init__(self, ctx: moderngl.Context):
        context = imgui.get_current_context()
        if context is None:
            raise RuntimeError("no current ImGui context: call imgui.create_context() first")
        self.ctx = ctx
        self._imgui_context = context
        self._state = GLStateQuery(ctx)
        self._programs = ProgramLibrary(ctx)
        self._program = self._programs.get(PROGRAM)
        self._program["u_texture"] = 0
        self._vbo = ctx.buffer(reserve=_INITIAL_BUFFER_BYTES, dynamic=True)
        self._ibo = ctx.buffer(reserve=_INITIAL_BUFFER_BYTES, dynamic=True)
        self._vao = ctx.vertex_array(
            self._program,
            [(self._vbo, _VERTEX_FORMAT, "in_position", "in_uv", "in_color")],
            index_buffer=self._ibo,
            index_element_size=4,
        )
        self._imgui_textures: dict[int, moderngl.Texture] = {}
        self._user_textures: dict[int, moderngl.Texture] = {}
        self.texture_creations = 0
        self.texture_updates = 0

        io = imgui.get_io()
        io.backend_flags |= (
            imgui.BackendFlags_.renderer_has_textures | imgui.BackendFlags_.renderer_has_vtx_offset
        )
        max_size = int(ctx.info["GL_MAX_TEXTURE_SIZE"])
        platform_io = imgui.get_platform_io()
        platform_io.renderer_texture_max_width = max_size
        platform_io.renderer_texture_max_height = max_size

    @property
    def live_textures(self) -> int:
        """Number of GPU textures currently held for ImGui (not counting registered ones)."""
        return len(self._imgui_textures)

    def register_texture(self, texture: moderngl.Texture) -> imgui.ImTextureRef:
        """Make an application texture drawable with ``imgui.image``.

        The renderer does not own it: release it yourself, after
        :meth:`unregister_texture` or once the UI stops drawing it.

        Parameters
        ----------
        texture
            A 2D texture of this renderer's context. ImGui multiplies its RGBA by
            the vertex colour and writes the result unconverted.

        Returns
        -------
        imgui.ImTextureRef
            Pass it to ``imgui.image(ref, (w, h))``.
        """
        if texture.ctx is not self.ctx:
            raise ValueError("texture belongs to another moderngl context")
        self._user_textures[texture.glo] = texture
        return imgui.ImTextureRef(texture.glo)

    def unregister_texture(self, texture: moderngl.Texture) -> None:
        """Forget a texture given to :meth:`register_texture`; unknown ones are ignored."""
        self._user_textures.pop(texture.glo, None)

    def render(self, draw_data: imgui.ImDrawData) -> None:
        """Process texture requests, then draw ``draw_data`` into the bound framebuffer.

        The viewport is set to the display rectangle scaled by
        ``draw_data.framebuffer_scale``, anchored at the framebuffer's origin.
        Blending, depth test, face culling, scissor, viewport and polygon mode
        are restored afterwards; the program, vertex array and texture unit 0
        bindings are not, as every moderngl draw binds its own.

        Parameters
        ----------
        draw_data
            ``imgui.get_draw_data()`` after ``imgui.render()``.
        """
        if self._vao is None:
            raise RuntimeError("ImGuiRenderer used after release()")
        for tex in draw_data.textures or ():
            if tex.status != imgui.ImTextureStatus.ok:
                self._update_texture(tex)

        scale = draw_data.framebuffer_scale
        fb_width = int(draw_data.display_size.x * scale.x)
        fb_height = int(draw_data.display_size.y * scale.y)
        if fb_width <= 0 or fb_height <= 0 or draw_data.total_idx_count == 0:
            return
        draws = self._upload(draw_data)

        saved = self._state.capture()
        ctx = self.ctx
        ctx.enable(moderngl.BLEND)
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        ctx.blend_equation = moderngl.FUNC_ADD
        ctx.blend_func = (
            moderngl.SRC_ALPHA,
            moderngl.ONE_MINUS_SRC_ALPHA,
            moderngl.ONE,
            moderngl.ONE_MINUS_SRC_ALPHA,
        )
        ctx.wireframe = False
        ctx.viewport = (0, 0, fb_width, fb_height)
        left, top = draw_data.display_pos.x, draw_data.display_pos.y
        width, height = draw_data.display_size.x, draw_data.display_size.y
        self._program["u_scale"] = (2.0 / width, -2.0 / height)
        self._program["u_offset"] = (-1.0 - 2.0 * left / width, 1.0 + 2.0 * top / height)
        try:
            bound_id = None
            for first, count, tex_id, clip in draws:
                x0 = max((clip.x - left) * scale.x, 0.0)
                y0 = max((clip.y - top) * scale.y, 0.0)
                x1 = min((clip.z - left) * scale.x, float(fb_width))
                y1 = min((clip.w - top) * scale.y, float(fb_height))
                if x1 <= x0 or y1 <= y0:
                    continue
                ctx.scissor = (int(x0), int(fb_height - y1), int(x1 - x0), int(y1 - y0))
                if tex_id != bound_id:
                    self.texture(tex_id).use(0)
                    bound_id = tex_id
                self._vao.render(moderngl.TRIANGLES, vertices=count, first=first)
        finally:
            saved.restore(ctx)

    def release(self) -> None:
        """Free every GPU object; safe to call twice.

        If the ImGui context it was made for is still current, its textures are
        marked destroyed (ImGui re-requests them from a later renderer) and the
        backend flags are cleared. Call it before ``imgui.destroy_context()``.
        """
        if self._vao is None:
            return
        for texture in self._imgui_textures.values():
            texture.release()
        if imgui.get_current_context() is self._imgui_context:
            for tex in imgui.get_platform_io().textures:
                if tex.tex_id in self._imgui_textures:
                    tex.set_tex_id(0)
                    tex.status = imgui.ImTextureStatus.destroyed
            imgui.get_io().backend_flags &= ~(
                imgui.BackendFlags_.renderer_has_textures
                | imgui.BackendFlags_.renderer_has_vtx_offset
            )
        self._imgui_textures.clear()
        self._user_textures.clear()
        self._vao.release()
        self._vbo.release()
        self._ibo.release()
        self._programs.release()
        self._vao = None

    def texture(self, tex_id: int) -> moderngl.Texture:
        """The moderngl texture behind an ImGui texture id (``ImTextureData.tex_id``).

        Raises
        ------
        KeyError
            If the id is neither an ImGui texture of this renderer nor registered.
        """
        texture = self._imgui_textures.get(tex_id, self._user_textures.get(tex_id))
        if texture is None:
            raise KeyError(
                f"ImGui draws texture id {tex_id}, which is neither an ImGui texture nor one "
                "given to ImGuiRenderer.register_texture()"
            )
        return texture

    def _upload(self, draw_data: imgui.ImDrawData) -> list[tuple[int, int, int, imgui.ImVec4]]:
        """Write all draw lists into one vertex and one uint32 index buffer.

        Indices are rebased to absolute vertex numbers (list start plus the
        command's ``vtx_offset``), so any ImDrawIdx width and vtx offsets need
        no base-vertex draw call.

        Returns
        -------
        list of (first_index, index_count, texture_id, clip_rect)
        """
        idx_dtype = _INDEX_DTYPE[imgui.INDEX_SIZE]
        vertex_chunks = []
        index_chunks = []
        draws = []
        vertex_base = 0
        index_base = 0
        for cmd_list in draw_data.cmd_lists:
            n_vtx = cmd_list.vtx_buffer.size()
            n_idx = cmd_list.idx_buffer.size()
            if n_idx == 0:
                continue
            vertex_chunks.append(
                _view(cmd_list.vtx_buffer.data_address(), n_vtx * imgui.VERTEX_SIZE, np.uint8)
            )
            indices = _view(cmd_list.idx_buffer.data_address(), n_idx, idx_dtype).astype(np.uint32)
            indices += vertex_base
            for cmd in cmd_list.cmd_buffer:
                if cmd.elem_count == 0:
                    continue
                if cmd.vtx_offset:
                    indices[cmd.idx_offset : cmd.idx_offset + cmd.elem_count] += cmd.vtx_offset
                draws.append(
                    (index_base + cmd.idx_offset, cmd.elem_count, cmd.get_tex_id(), cmd.clip_rect)
                )
            index_chunks.append(indices)
            vertex_base += n_vtx
            index_base += n_idx
        _write(self._vbo, np.concatenate(vertex_chunks))
        _write(self._ibo, np.concatenate(index_chunks))
        return draws

    def _update_texture(self, tex: imgui.ImTextureData) -> None:
        status = tex.status
        if status == imgui.ImTextureStatus.want_create:
            self._create_texture(tex)
        elif status == imgui.ImTextureStatus.want_updates:
            texture = self._imgui_textures[tex.tex_id]
            pixels = _pixels(tex)
            for rect in tex.updates:
                block = pixels[rect.y : rect.y + rect.h, rect.x : rect.x + rect.w]
                texture.write(
                    np.ascontiguousarray(block), viewport=(rect.x, rect.y, rect.w, rect.h)
                )
            tex.status = imgui.ImTextureStatus.ok
            self.texture_updates += 1
        elif status == imgui.ImTextureStatus.want_destroy and tex.unused_frames > 0:
            self._imgui_textures.pop(tex.tex_id).release()
            tex.set_tex_id(0)
            tex.status = imgui.ImTextureStatus.destroyed

    def _create_texture(self, tex: imgui.ImTextureData) -> None:
        components = _COMPONENTS.get(tex.format)
        if components is None:
            raise ValueError(f"unsupported ImGui texture format {tex.format!r}")
        texture = self.ctx.texture((tex.width, tex.height), components, data=_pixels(tex))
        if components == 1:
            texture.swizzle = "111R"
        texture.filter = (moderngl.LINEAR, moderngl.LINEAR)
        texture.repeat_x = False
        texture.repeat_y = False
        self._imgui_textures[texture.glo] = texture
        tex.set_tex_id(texture.glo)
        tex.status = imgui.ImTextureStatus.ok
        self.texture_creations += 1


def _view(address: int, count: int, dtype: type[np.generic]) -> np.ndarray:
    """``count`` elements of ``dtype`` at ``address``, without copying."""
    nbytes = count * np.dtype(dtype).itemsize
    return np.frombuffer((ctypes.c_ubyte * nbytes).from_address(address), dtype=dtype)


def _pixels(tex: imgui.ImTextureData) -> np.ndarray:
    """The CPU copy of an ImGui texture, (height, width, bytes_per_pixel) uint8, row 0 on top."""
    return tex.get_pixels_array().reshape(tex.height, tex.width, tex.bytes_per_pixel)


def _write(buffer: moderngl.Buffer, data: np.ndarray) -> None:
    """Replace the contents of a streaming buffer, growing it by doubling."""
    size = buffer.size
    while size < data.nbytes:
        size *= 2
    buffer.orphan(size)
    buffer.write(data)
