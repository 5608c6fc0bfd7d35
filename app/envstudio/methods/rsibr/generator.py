"""The per-frame map generation of seed 002 §3.2–§3.4 and §4 on the GPU.

For the destination frame T_d: find the view triangle and its spherical
barycentric weights (core.icosahedron.view_weights), draw each of its (up to)
three source maps through the tessellated disk (shaders/rsibr/warp.glsl) into an
RGBA32F accumulation target with additive blending, divide by the summed weight
(shaders/rsibr/resolve.glsl) into the generated map, and build its mip chain.
Sources whose weight is 0 are skipped, so at a sample view the generated map is
that sample's map.

The disk (§3.3): ``rings`` rings of ``4 rings`` vertices at radii
½ sin(π/2 · k / rings) (finer toward the rim, where the warp is least linear),
the last of them at ``RIM``, just inside the rim (where g_mirror is still
invertible), a centre vertex, and one outer ring at radius ½√2 + 0.02 that covers
the square's corners with the values of the rim (shaders/rsibr/warp.glsl
evaluates its vertices at ``RIM``), so that the mip chain is not darkened or
lit by whatever lies outside the disc.
"""

from __future__ import annotations

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.icosahedron import view_weights
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.gpu.programs import ProgramLibrary
from envstudio.methods.rsibr.warp import singularity_uv
from envstudio.plugin import set_uniform

__all__ = ["MapGenerator", "disk_mesh"]

_WARP_CODES = {"mirror": 0, "normal": 1}
#: Radius of the last ring inside the disc (the RIM of shaders/rsibr/warp.glsl).
RIM = 0.49995


def disk_mesh(rings: int) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.int32]]:
    """The tessellated disk of §3.3 in sphere-map coordinates.

    Parameters
    ----------
    rings
        Rings inside the disc (≥ 1); each has ``4 rings`` vertices (at least 8).

    Returns
    -------
    vertices : (V, 2) float32
        (s, t) of each vertex.
    triangles : (T, 3) int32
        Counter-clockwise in (s, t).
    """
    sectors = max(8, 4 * rings)
    angles = 2.0 * np.pi * np.arange(sectors) / sectors
    unit = np.stack([np.cos(angles), np.sin(angles)], axis=-1)
    radii = [0.5 * np.sin(0.5 * np.pi * k / rings) for k in range(1, rings)]
    radii += [RIM, 0.5 * np.sqrt(2.0) + 0.02]
    vertices = [np.array([[0.5, 0.5]])] + [0.5 + r * unit for r in radii]
    triangles = [[0, 1 + i, 1 + (i + 1) % sectors] for i in range(sectors)]
    for ring in range(len(radii) - 1):
        a, b = 1 + ring * sectors, 1 + (ring + 1) * sectors
        for i in range(sectors):
            j = (i + 1) % sectors
            triangles += [[a + i, b + i, b + j], [a + i, b + j, a + j]]
    return np.concatenate(vertices).astype(np.float32), np.asarray(triangles, dtype=np.int32)


class MapGenerator:
    """Warps and blends source maps into a generated, mipmapped sphere map; owns its targets.

    Parameters
    ----------
    ctx, programs
        Context and its program library.
    size
        Generated map edge n in texels.
    """

    def __init__(self, ctx: moderngl.Context, programs: ProgramLibrary, size: int):
        self.ctx = ctx
        self.programs = programs
        self.size = size
        self.accumulation = ctx.texture((size, size), 4, dtype="f4")
        self.accumulation.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self._accumulation_fb = ctx.framebuffer(color_attachments=[self.accumulation])
        self.texture = ctx.texture((size, size), 4, dtype="f4")
        self.texture.repeat_x = self.texture.repeat_y = False
        self._texture_fb = ctx.framebuffer(color_attachments=[self.texture])
        self.texture.build_mipmaps()
        self.texture.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        self._pass = FullscreenPass(ctx)
        self._rings = 0
        self._vbo: moderngl.Buffer | None = None
        self._ibo: moderngl.Buffer | None = None
        self._vao: moderngl.VertexArray | None = None
        #: Indices and weights of the last generated map's sources (for the panel).
        self.sources: tuple[npt.NDArray[np.int32], npt.NDArray[np.float64]] | None = None

    def generate(
        self,
        maps: list[moderngl.Texture],
        views: npt.ArrayLike,
        frames: npt.ArrayLike,
        faces: npt.ArrayLike,
        frame_d: npt.ArrayLike,
        warp: str,
        rings: int = 16,
        fade: bool = True,
        fade_radius: float = 0.1,
        per_pixel: bool = False,
        only: int | None = None,
    ) -> moderngl.Texture:
        """The map for destination frame ``frame_d`` (§4's warp and blending loop).

        Parameters
        ----------
        maps
            Source textures, one per view (clamped, linear filtering).
        views : (V, 3) float
            Their view directions.
        frames : (V, 3, 3) float
            Their frames T_j.
        faces : (F, 3) int
            Triangles of the views.
        frame_d : (3, 3) float
            Destination frame T_d (columns x, y, z of the camera in world space).
        warp
            ``mirror`` or ``normal`` (§3.3).
        rings
            Disk tessellation (:func:`disk_mesh`).
        fade, fade_radius
            Singularity fade (§3.3) and its radius in map units (normal warp: in n·v_s).
        per_pixel
            Evaluate the warp per fragment instead of per disk vertex.
        only
            Draw only the face's source at this position (0, 1, 2): the result is that
            source warped into T_d alone (faded near its singularity, divided by its
            weight), Figure 4's middle row. :attr:`sources` still lists all three.

        Returns
        -------
        moderngl.Texture
            :attr:`texture`, (n, n) RGBA32F with mips, valid until the next call.
        """
        frame_d = np.asarray(frame_d, dtype=np.float64)
        _, indices, weights = view_weights(frame_d[:, 2], views, faces)
        self.sources = (indices, weights)
        program = self.programs.get("rsibr/warp.glsl")
        vao = self._disk(program, rings)
        self._accumulation_fb.use()
        self._accumulation_fb.clear(0.0, 0.0, 0.0, 0.0)
        self.ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        self.ctx.enable(moderngl.BLEND)
        self.ctx.blend_func = moderngl.ONE, moderngl.ONE
        self.ctx.blend_equation = moderngl.FUNC_ADD
        set_uniform(program, "u_warp", _WARP_CODES[warp])
        set_uniform(program, "u_per_pixel", bool(per_pixel))
        set_uniform(program, "u_fade", bool(fade))
        set_uniform(program, "u_fade_radius", float(fade_radius))
        set_uniform(program, "u_source", 0)
        frames = np.asarray(frames, dtype=np.float64)
        for position, (index, weight) in enumerate(zip(indices, weights, strict=True)):
            if only is not None:
                if position != only:
                    continue
                weight = 1.0
            elif weight <= 0.0:
                continue
            maps[index].use(location=0)
            set_uniform(program, "u_dest_to_source", frames[index].T @ frame_d)
            set_uniform(program, "u_singularity", tuple(singularity_uv(frames[index], frame_d)))
            set_uniform(program, "u_weight", float(weight))
            vao.render(moderngl.TRIANGLES)
        self.ctx.disable(moderngl.BLEND)
        self.ctx.blend_func = moderngl.DEFAULT_BLENDING
        resolve = self.programs.get("rsibr/resolve.glsl")
        self.accumulation.use(location=0)
        set_uniform(resolve, "u_accumulation", 0)
        self._texture_fb.use()
        self._pass.draw(resolve)
        self.texture.build_mipmaps()
        return self.texture

    def _disk(self, program: moderngl.Program, rings: int) -> moderngl.VertexArray:
        """The disk's vertex array, rebuilt when the tessellation changes."""
        if rings != self._rings or self._vao is None:
            self._release_disk()
            vertices, triangles = disk_mesh(rings)
            self._vbo = self.ctx.buffer(vertices.tobytes())
            self._ibo = self.ctx.buffer(triangles.tobytes())
            self._vao = self.ctx.vertex_array(
                program, [(self._vbo, "2f", "in_uv")], index_buffer=self._ibo, index_element_size=4
            )
            self._rings = rings
        return self._vao

    def _release_disk(self) -> None:
        for obj in (self._vao, self._vbo, self._ibo):
            if obj is not None:
                obj.release()
        self._vao = self._vbo = self._ibo = None

    def release(self) -> None:
        """Free every target and buffer; safe to call twice."""
        self._release_disk()
        self._pass.release()
        for obj in (self._accumulation_fb, self.accumulation, self._texture_fb, self.texture):
            if obj is not None:
                obj.release()
        self._accumulation_fb = self.accumulation = self._texture_fb = self.texture = None
