"""SH projection and light extraction of a cube map on the GPU (seed 000 section 5.1.1).

The GPU twin of :class:`envstudio.core.sh_lights.DiffuseProjector` for cube maps,
used when the environment changes every frame (method ``kautz`` with ``dynamic``):
no pixel leaves the GPU. Three compute dispatches (OpenGL 4.3):

1. shaders/prefilter/sh_project.glsl, PASS 1 — one work group per cube-face tile
   (8 × 8 tiles per face): Σ L Y_i Δω per coefficient and channel, and Σ lum Δω;
2. the same file, PASS 2 (only with lights) — the threshold T = τ · mean luminance
   from the tile powers, then the same sums for the excess above T, its luminance
   moment, power and RGB power;
3. shaders/prefilter/sh_reduce.glsl — one work group: ranks the tiles by excess power,
   turns the strongest into cap lights, sums the rest into the SH coefficients,
   multiplies by Â_l and writes the uniform block rows of shaders/common/sh_irradiance.glsl.
"""

from __future__ import annotations

import moderngl

from envstudio.core.sh_bands import BAND_SETS, band_indices
from envstudio.gpu.programs import ProgramLibrary
from envstudio.gpu.uniforms import set_uniform

__all__ = ["TILES_PER_EDGE", "GpuDiffuseProjector", "block_rows"]

#: Cube-face tiles per face edge (core.sh_lights.DiffuseProjector's default).
TILES_PER_EDGE = 8
_TILES = 6 * TILES_PER_EDGE**2


def block_rows(coefficients: int, lights: int) -> int:
    """Number of vec4 rows of the uniform block for a band set and light count."""
    return len(band_indices(BAND_SETS[coefficients])[0]) + 2 * lights


class GpuDiffuseProjector:
    """Projects one level of a cube map into a uniform-block buffer, every frame if need be.

    Parameters
    ----------
    ctx, programs
        Context (OpenGL 4.3 or later) and its program library.
    """

    def __init__(self, ctx: moderngl.Context, programs: ProgramLibrary):
        self.ctx = ctx
        self.programs = programs
        count = len(band_indices(BAND_SETS[max(BAND_SETS)])[0])
        self._full = ctx.buffer(reserve=_TILES * (3 * count + 1) * 4)
        self._excess = ctx.buffer(reserve=_TILES * (3 * count + 7) * 4)

    def project(
        self,
        cube: moderngl.TextureCube,
        level: int,
        coefficients: int,
        lights: int,
        threshold: float,
        rows: moderngl.Buffer,
    ) -> None:
        """Decompose and project level ``level`` of ``cube`` into ``rows``.

        Parameters
        ----------
        cube
            RGBA32F cube map; the faces of ``level`` must be a multiple of 8 texels wide.
        level
            Mip level read (exact texels, by image load).
        coefficients
            9, 25 or 49 (core.sh_bands.BAND_SETS).
        lights
            K cap lights to extract (0: plain projection).
        threshold
            τ of the light threshold T = τ · mean luminance.
        rows
            Buffer of at least :func:`block_rows` vec4 rows, receiving
            core.sh_lights.DiffuseLighting.block's layout.
        """
        size = cube.size[0] >> level
        if size < TILES_PER_EDGE or size % TILES_PER_EDGE:
            raise ValueError(f"level {level} faces are {size} texels, not a multiple of 8")
        if rows.size < block_rows(coefficients, lights) * 16:
            raise ValueError("the rows buffer is too small for this band set and light count")
        defines = {"SH_COEFFICIENTS": coefficients, "TILES_PER_EDGE": TILES_PER_EDGE}
        cube.bind_to_image(0, read=True, write=False, level=level)
        self._full.bind_to_storage_buffer(1)
        self._excess.bind_to_storage_buffer(2)
        rows.bind_to_storage_buffer(3)
        barrier = moderngl.SHADER_STORAGE_BARRIER_BIT
        first = self.programs.compute("prefilter/sh_project.glsl", {**defines, "PASS": 1})
        set_uniform(first, "u_face_size", size)
        first.run((_TILES + 63) // 64)
        if lights:
            self.ctx.memory_barrier(barrier)
            second = self.programs.compute("prefilter/sh_project.glsl", {**defines, "PASS": 2})
            set_uniform(second, "u_face_size", size)
            set_uniform(second, "u_threshold", float(threshold))
            second.run((_TILES + 63) // 64)
        self.ctx.memory_barrier(barrier)
        reduce = self.programs.compute("prefilter/sh_reduce.glsl", {**defines, "LIGHTS": lights})
        reduce.run(1)
        self.ctx.memory_barrier(barrier | moderngl.UNIFORM_BARRIER_BIT)

    def release(self) -> None:
        """Free the partial-sum buffers; safe to call twice."""
        for buf in (self._full, self._excess):
            if buf is not None:
                buf.release()
        self._full = self._excess = None
