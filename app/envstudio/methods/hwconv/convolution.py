"""The GPU passes of seed 004 §5.2: dual paraboloid with border, maps S and L, their blend.

Algorithm (§5.2, the paper's 14 steps) and where each step happens here::

    mip-map the parabolic map, load it        set_source: envmap.conversions.cube_to_paraboloid
                                              from the static cube, TextureArray.build_mipmaps
    r_s, r_l, shrink factors (steps 3–5)      radii.plan_filters
    1–2  orthographic camera, d² in alpha     one fragment per texel (full-screen triangle)
    6–8  draw shrunk, sample Phong, convolve  shaders/hwconv/convolve.glsl, per face and
                                              kernel, reading mip level log2 s
    9    store as texture                     the pass renders straight into a texture
    10–12 draw S, blend L with d², store      shaders/hwconv/blend.glsl (skipped in one pass:
                                              S is the result)
    13–14 real camera, draw the reflector     shaders/hwconv/hwconv.glsl (methods.hwconv.method)

Faces are kept as separate 2D textures (front = 0, z ≥ 0; back = 1): moderngl cannot
attach one layer of an array to a framebuffer, and this way no pass copies a face.
Every texture is RGBA32F: the paper's hardware clamped radiance to [0, 1], ours is float.
"""

from __future__ import annotations

import contextlib

import moderngl
import numpy as np

from envstudio.envmap.conversions import cube_to_paraboloid
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.gpu.programs import ProgramLibrary
from envstudio.methods.hwconv.radii import MAX_KERNEL, FilterPlan, kernel_weights
from envstudio.plugin import set_uniform

__all__ = ["FaceMaps", "ParaboloidConvolution"]

_CONVOLVE = "hwconv/convolve.glsl"
_BLEND = "hwconv/blend.glsl"
_EXACT = "hwconv/exact.glsl"


class FaceMaps:
    """The two faces of one dual-paraboloid map as 2D RGBA32F textures with framebuffers.

    Parameters
    ----------
    ctx
        The context that owns them.
    size
        Texels across each face.
    """

    def __init__(self, ctx: moderngl.Context, size: int):
        self.size = int(size)
        self.faces = []
        self.framebuffers = []
        for _ in range(2):
            tex = ctx.texture((self.size, self.size), 4, dtype="f4")
            tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
            tex.repeat_x, tex.repeat_y = False, False
            self.faces.append(tex)
            self.framebuffers.append(ctx.framebuffer([tex]))

    def use(self, front: int, back: int) -> None:
        """Bind the front face to texture unit ``front`` and the back face to ``back``."""
        self.faces[0].use(location=front)
        self.faces[1].use(location=back)

    def read(self) -> np.ndarray:
        """(2, n, n, 3) float32 texel values, row 0 = t = 0 (core.paraboloid's layout)."""
        return np.stack(
            [
                np.frombuffer(tex.read(), np.float32).reshape(self.size, self.size, 4)[..., :3]
                for tex in self.faces
            ]
        )

    def release(self) -> None:
        """Free the textures and framebuffers; safe to call twice."""
        for obj in (*self.framebuffers, *self.faces):
            obj.release()
        self.framebuffers, self.faces = [], []


class ParaboloidConvolution:
    """Owns the source dual paraboloid, maps S and L and the blended map of §5.2.

    Parameters
    ----------
    ctx, programs
        Context and its program library.
    """

    def __init__(self, ctx: moderngl.Context, programs: ProgramLibrary):
        self.ctx = ctx
        self.programs = programs
        self.source: moderngl.TextureArray | None = None
        self.maps: dict[str, FaceMaps] = {}
        self._quad = FullscreenPass(ctx)
        self._face_size = 0
        self._border = 0

    def set_source(self, cube: moderngl.TextureCube, size: int, border: int) -> None:
        """Resample ``cube`` into the dual paraboloid with border and build its mip chain.

        Parameters
        ----------
        cube
            The environment as seen from the reflector (GpuScene.static_environment).
        size, border
            Texels across the unit disc and of border on each side; the faces are
            size + 2 · border texels wide.
        """
        face_size = size + 2 * border
        self._release_source()
        self.source = cube_to_paraboloid(self.ctx, self.programs, cube, face_size, border)
        self.source.build_mipmaps()
        self.source.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        self._face_size, self._border = face_size, border

    def filter(self, plan: FilterPlan, maps: set[str], timer=None) -> None:
        """Run the passes that make ``maps`` (then in :attr:`maps` by name).

        Parameters
        ----------
        plan
            Kernels and shrink factors (its face size must be the source's).
        maps
            Any of ``small`` (S), ``large`` (L), ``blended`` (needs both) and ``exact``
            (the shift-variant kernel, at S's resolution). ``{"small"}`` alone is the
            paper's 1-pass column.
        timer
            PassTimer for the passes ``hwconv.small``, ``hwconv.large``, ``hwconv.blend``,
            ``hwconv.exact``.
        """
        if self.source is None or plan.face_size != self._face_size:
            raise RuntimeError("set_source with the plan's size and border first")
        if "blended" in maps:
            maps = maps | {"small", "large"}
        scope = self.ctx.scope(self.ctx.fbo, enable_only=moderngl.NOTHING)
        try:
            with scope:
                for which in ("small", "large"):
                    if which in maps:
                        with _measure(timer, f"hwconv.{which}"):
                            self._convolve(plan, which)
                if "blended" in maps:
                    with _measure(timer, "hwconv.blend"):
                        self._blend()
                if "exact" in maps:
                    with _measure(timer, "hwconv.exact"):
                        self._exact(plan)
        finally:
            scope.release()

    def _target(self, name: str, size: int) -> FaceMaps:
        maps = self.maps.get(name)
        if maps is None or maps.size != size:
            if maps is not None:
                maps.release()
            maps = self.maps[name] = FaceMaps(self.ctx, size)
        return maps

    def _convolve(self, plan: FilterPlan, which: str) -> None:
        """Steps 6–9 for one kernel: both faces at mip level log2 s into map S or L."""
        level = plan.level(which)
        target = self._target(which, max(self._face_size >> level, 1))
        program = self.programs.get(_CONVOLVE, {"MAX_KERNEL": MAX_KERNEL})
        weights = np.zeros(MAX_KERNEL * MAX_KERNEL, np.float32)
        kernel = kernel_weights(plan, which)
        weights[: kernel.size] = kernel.ravel()
        self.source.use(location=0)
        set_uniform(program, "u_source", 0)
        set_uniform(program, "u_level", level)
        set_uniform(program, "u_radius", plan.max_kernel // 2)
        set_uniform(program, "u_weights", weights)
        for face in range(2):
            target.framebuffers[face].use()
            set_uniform(program, "u_face", face)
            self._quad.draw(program)

    def _blend(self) -> None:
        """Steps 10–12: (1 − d²) S + d² L per texel of both faces at full size."""
        target = self._target("blended", self._face_size)
        program = self.programs.get(_BLEND)
        set_uniform(program, "u_small", 0)
        set_uniform(program, "u_large", 1)
        set_uniform(program, "u_size", float(self._face_size))
        set_uniform(program, "u_border", float(self._border))
        for face in range(2):
            self.maps["small"].faces[face].use(location=0)
            self.maps["large"].faces[face].use(location=1)
            target.framebuffers[face].use()
            self._quad.draw(program)

    def _exact(self, plan: FilterPlan) -> None:
        """The shift-variant kernel (shaders/hwconv/exact.glsl) at S's resolution.

        Taps read L's mip level, 2K + 1 each side: the window covers the exact lobe's
        reach beyond the rim (radii.outward_radius ≤ 2 r_l).
        """
        target = self._target("exact", max(self._face_size >> plan.level("small"), 1))
        program = self.programs.get(_EXACT)
        self.source.use(location=0)
        set_uniform(program, "u_source", 0)
        set_uniform(program, "u_level", plan.level("large"))
        set_uniform(program, "u_radius", 2 * (plan.max_kernel // 2) + 1)
        set_uniform(program, "u_size", float(self._face_size))
        set_uniform(program, "u_border", float(self._border))
        set_uniform(program, "u_target_size", float(target.size))
        set_uniform(program, "u_exponent", float(plan.exponent))
        set_uniform(program, "u_epsilon", float(plan.epsilon))
        for face in range(2):
            target.framebuffers[face].use()
            set_uniform(program, "u_face", face)
            self._quad.draw(program)

    def _release_source(self) -> None:
        if self.source is not None:
            self.source.release()
        self.source = None

    def release(self) -> None:
        """Free the source, every map and the vertex arrays; safe to call twice."""
        self._release_source()
        for maps in self.maps.values():
            maps.release()
        self.maps = {}
        self._quad.release()


def _measure(timer, name: str):
    return timer.measure(name) if timer is not None else contextlib.nullcontext()
