"""The reference's accumulation on the GPU: the sums of the batch means, and the batch in progress.

Every batch is drawn with additive blending into ``batch`` (per pixel the sum
of its estimates, RGB, and their count, A); :meth:`Accumulation.add_batch`
then adds the batch's mean and its square to ``sum`` and ``sum_sq``
(shaders/reference/merge_batch.glsl) and clears it. Each pixel's share of a
batch (methods/reference/sample_allocation.py) reaches the shader as a texture.
"""

from __future__ import annotations

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.methods.reference.batch_statistics import (
    batch_variance,
    mean_of_batches,
    noise,
    standard_error,
)
from envstudio.methods.reference.sample_allocation import SampleAllocation
from envstudio.plugin import PairedEstimates

#: Sums, their squares and the batch: the traced estimate's and, with ``untraced_too``, the
#: untraced estimate's from the same samples (each RGBA32F, (w, h)).
SumTextures = tuple[moderngl.Texture, moderngl.Texture, moderngl.Texture]


class Accumulation:
    """The GPU targets of one accumulation and each pixel's sample allocation.

    Attributes
    ----------
    sum, sum_sq : moderngl.Texture or None
        RGBA32F, (w, h), row 0 at the bottom: per pixel the sum of the batch
        means (RGB, radiance) and the batch count (A), and the sum of the
        squared batch means. None before :meth:`ensure`.
    batch : moderngl.Texture or None
        RGBA32F, (w, h): the batch in progress (sum of estimates, count).
    untraced : (batch, sum, sum_sq) or None
        The untraced estimate's batch and sums (``untraced_too``), else None.
    difference_sums : (sum, sum_sq) or None
        With ``untraced_too``, the sums of each batch's traced mean minus its untraced mean
        (the control variate's: shaders/reference/merge_difference.glsl), counted from the
        last :meth:`clear` or :meth:`write_sums` (a resumed accumulation's difference starts
        afresh: only the batches drawn since hold both), else None.
    batch_fbo : moderngl.Framebuffer or None
        ``batch`` (and the untraced batch) over ``depth``: where estimates are drawn.
    depth_fbo : moderngl.Framebuffer or None
        ``depth`` alone: the depth prepass's target.
    allocation : SampleAllocation
        Each pixel's samples per batch, and where its sample sequence continues.
    """

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self.sum: moderngl.Texture | None = None
        self.sum_sq: moderngl.Texture | None = None
        self.batch: moderngl.Texture | None = None
        self.untraced: SumTextures | None = None
        self.difference_sums: tuple[moderngl.Texture, moderngl.Texture] | None = None
        self.batch_fbo: moderngl.Framebuffer | None = None
        self.depth_fbo: moderngl.Framebuffer | None = None
        self.allocation = SampleAllocation.plain((1, 1))
        self.allocation_texture: moderngl.Texture | None = None  # (units, m) per pixel
        self._sums_fbo: moderngl.Framebuffer | None = None
        self._depth: moderngl.Renderbuffer | None = None

    @property
    def size(self) -> tuple[int, int] | None:
        """(w, h) of the targets in pixels; None before :meth:`ensure`."""
        return None if self.sum is None else self.sum.size

    def ensure(self, size: tuple[int, int], untraced_too: bool) -> None:
        """Make the targets for ``size`` (w, h), with the untraced ones if ``untraced_too``;
        kept when they already fit."""
        if self.size == tuple(size) and (self.untraced is not None) == untraced_too:
            return
        self.release()
        self.sum = self.ctx.texture(size, 4, dtype="f4")
        self.sum_sq = self.ctx.texture(size, 4, dtype="f4")
        self._sums_fbo = self.ctx.framebuffer([self.sum, self.sum_sq])
        self.batch = self.ctx.texture(size, 4, dtype="f4")
        self._depth = self.ctx.depth_renderbuffer(size)
        colours = [self.batch]
        if untraced_too:
            self.untraced = tuple(self.ctx.texture(size, 4, dtype="f4") for _ in range(3))
            self.difference_sums = tuple(self.ctx.texture(size, 4, dtype="f4") for _ in range(2))
            colours.append(self.untraced[0])
        self.batch_fbo = self.ctx.framebuffer(colours, self._depth)
        self.depth_fbo = self.ctx.framebuffer(depth_attachment=self._depth)
        self.allocation_texture = self.ctx.texture(size, 2, dtype="f4")
        self.allocation_texture.filter = (moderngl.NEAREST, moderngl.NEAREST)

    def clear(self) -> None:
        """Start over: no batches, every pixel at the plain rate."""
        w, h = self.size
        self._sums_fbo.clear(0.0, 0.0, 0.0, 0.0)
        self.batch_fbo.clear(0.0, 0.0, 0.0, 0.0)
        for tex in (*(self.untraced or ())[1:], *(self.difference_sums or ())):
            tex.write(np.zeros((h, w, 4), np.float32).tobytes())
        self.set_allocation(SampleAllocation.plain((h, w)))

    def add_batch(
        self, merge: moderngl.ComputeShader, merge_difference: moderngl.ComputeShader
    ) -> None:
        """Add the finished batch's mean per pixel (and its square) to the sums; clear it.

        ``merge`` is shaders/reference/merge_batch.glsl. With ``untraced_too``
        the untraced batch is merged into its own sums the same way, and the difference of
        the two means into :attr:`difference_sums` (``merge_difference``,
        shaders/reference/merge_difference.glsl).
        """
        self.ctx.memory_barrier(moderngl.ALL_BARRIER_BITS)
        w, h = self.size
        if self.difference_sums is not None:
            self.batch.bind_to_image(0, read=True, write=False)
            self.difference_sums[0].bind_to_image(1, read=True, write=True)
            self.difference_sums[1].bind_to_image(2, read=True, write=True)
            self.untraced[0].bind_to_image(3, read=True, write=False)
            merge_difference.run((w + 7) // 8, (h + 7) // 8)
            self.ctx.memory_barrier(moderngl.ALL_BARRIER_BITS)
        sets = [(self.batch, self.sum, self.sum_sq)]
        if self.untraced is not None:
            sets.append(self.untraced)
        for batch, total, squares in sets:
            batch.bind_to_image(0, read=True, write=False)
            total.bind_to_image(1, read=True, write=True)
            squares.bind_to_image(2, read=True, write=True)
            merge.run((w + 7) // 8, (h + 7) // 8)
            self.ctx.memory_barrier(moderngl.ALL_BARRIER_BITS)
        self.batch_fbo.clear(0.0, 0.0, 0.0, 0.0)

    # -- reading -----------------------------------------------------------------------------

    def read(self) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """(h, w, 4) float32 ``sum`` and ``sum_sq``, row 0 at the top."""
        return _read_texture(self.sum), _read_texture(self.sum_sq)

    def read_untraced(self) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]] | None:
        """(h, w, 4) float32 sums of the untraced estimate as :meth:`read`; None without one."""
        if self.untraced is None:
            return None
        return _read_texture(self.untraced[1]), _read_texture(self.untraced[2])

    def estimate(self) -> npt.NDArray[np.float32]:
        """(h, w, 3) mean radiance, row 0 at the top (0 where no sample landed)."""
        total, _ = self.read()
        return mean_of_batches(total)

    def standard_error(self) -> npt.NDArray[np.float32]:
        """(h, w, 3) standard error of :meth:`estimate` (inf with fewer than two batches)."""
        return standard_error(*self.read())

    def coverage(self) -> npt.NDArray[np.bool_]:
        """(h, w) True where samples landed."""
        total, _ = self.read()
        return total[..., 3] > 0

    def noise(self) -> float:
        """Median relative standard error of :meth:`estimate` (:func:`noise`)."""
        return noise(*self.read())

    def untraced_estimate(self) -> npt.NDArray[np.float32] | None:
        """(h, w, 3) the untraced estimate as :meth:`estimate`; None without one."""
        sums = self.read_untraced()
        return None if sums is None else mean_of_batches(sums[0])

    def paired(self) -> PairedEstimates | None:
        """The traced and untraced estimates with their errors and the error of their
        difference (:class:`PairedEstimates`); None without ``untraced_too``."""
        if self.difference_sums is None:
            return None
        traced, untraced = self.read(), self.read_untraced()
        difference = [_read_texture(tex) for tex in self.difference_sums]
        return PairedEstimates(
            traced=mean_of_batches(traced[0]),
            traced_error=standard_error(*traced),
            untraced=mean_of_batches(untraced[0]),
            untraced_error=standard_error(*untraced),
            difference_error=standard_error(*difference),
        )

    def untraced_noise(self) -> float:
        """The untraced estimate's :meth:`noise` (inf without one)."""
        sums = self.read_untraced()
        return float("inf") if sums is None else noise(*sums)

    # -- writing -----------------------------------------------------------------------------

    def write_sums(
        self,
        total: npt.NDArray[np.float32],
        squares: npt.NDArray[np.float32],
        untraced: tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]] | None,
    ) -> None:
        """Replace the sums by (h, w, 4) arrays as :meth:`read` gives them; ``untraced``
        (its total and squares) is written only where this accumulation has one."""
        pairs = [(self.sum, total), (self.sum_sq, squares)]
        if self.untraced is not None and untraced is not None:
            pairs += list(zip(self.untraced[1:], untraced, strict=True))
        for tex, array in pairs:
            tex.write(np.ascontiguousarray(array[::-1], np.float32).tobytes())
        for tex in self.difference_sums or ():  # not saved: the difference starts afresh
            tex.write(np.zeros((*total.shape[:2], 4), np.float32).tobytes())

    def reallocate(self, batches: int) -> None:
        """Set each pixel's samples per batch from its standard deviation (Neyman, floored)."""
        total, squares = self.read()
        variance = np.nan_to_num(batch_variance(total, squares), posinf=0.0).sum(-1)
        covered = total[..., 3] > 0
        self.set_allocation(self.allocation.reallocate(batches, variance, covered))

    def set_allocation(self, allocation: SampleAllocation) -> None:
        """Use ``allocation`` from the next batch on; the shader gets (units, m) per pixel."""
        self.allocation = allocation
        units, _ = allocation.at_batch(allocation.at)
        texels = np.dstack([units, allocation.multipliers]).astype(np.float32)[::-1]
        self.allocation_texture.write(np.ascontiguousarray(texels).tobytes())

    def release(self) -> None:
        """Free the targets; safe to call twice."""
        targets = (self.depth_fbo, self.batch_fbo, self._sums_fbo, self._depth)
        for obj in (*targets, self.sum, self.sum_sq, self.batch, self.allocation_texture):
            if obj is not None:
                obj.release()
        for tex in (*(self.untraced or ()), *(self.difference_sums or ())):
            tex.release()
        self.untraced = self.difference_sums = None
        self.depth_fbo = self.batch_fbo = self._sums_fbo = self._depth = None
        self.sum = self.sum_sq = self.batch = self.allocation_texture = None


def _read_texture(tex: moderngl.Texture) -> npt.NDArray[np.float32]:
    """(h, w, 4) float32 of an RGBA32F target, row 0 at the top."""
    w, h = tex.size
    return np.frombuffer(tex.read(), dtype=np.float32).reshape(h, w, 4)[::-1].copy()
