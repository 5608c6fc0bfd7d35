"""The window's passes: a batch in bands of rows within the frame budget, a coarse first pass.

In the window a batch over the whole image can take seconds on a software
renderer; the image is then processed in horizontal bands, as many per frame
as fit the budget, so the UI stays responsive. A batch is complete when the
bands have covered every row. The cost of a band is predicted from the
reflector pixels in its rows (counted from the depth prepass) times the last
measured cost per pixel, so rows of background cost nothing and a band never
grows past the reflector's edge into seconds of work. Until the first batch
is complete a coarse preview shows where no band has reached yet.
"""

from __future__ import annotations

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.plugin import set_uniform

#: The window's first pass: PREVIEW_SAMPLES per pixel at 1/PREVIEW_SCALE of the image's width
#: and height (1/16 of a default batch's work), so few of its pixels are a zero draw.
PREVIEW_SCALE = 4
PREVIEW_SAMPLES = 8


class WindowPasses:
    """Where the batch in progress stands within its bands, and the first pass's preview.

    Attributes
    ----------
    band_start : int
        The next band's first row, counted from the bottom (0: a batch starts).
    preview_made : bool
        Whether this accumulation's preview is drawn.
    """

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self.band_start = 0
        self.preview_made = False
        self._row_work: npt.NDArray[np.float64] | None = None  # (h,) from the bottom
        self._pixel_cost_s: float | None = None
        self._preview: moderngl.Texture | None = None
        self._preview_fbo: moderngl.Framebuffer | None = None

    def restart(self) -> None:
        """A new accumulation: its first batch from the first row, a new preview."""
        self.band_start = 0
        self.preview_made = False

    def showing_first_pass(self, batches: int) -> bool:
        """Whether the image still shows the first pass: bands over the preview."""
        return batches == 0 and self.preview_made

    def first_pass_progress(self, height: int) -> float:
        """Share (0 … 1) of the ``height`` rows the first batch has covered."""
        return self.band_start / max(height, 1)

    def count_row_work(
        self, depth_fbo: moderngl.Framebuffer, size: tuple[int, int], multipliers: npt.NDArray
    ) -> None:
        """Count each row's work from the depth prepass in ``depth_fbo`` of ``size`` (w, h):
        its covered pixels weighted by their (h, w) sample ``multipliers`` (row 0 at the top)."""
        w, h = size
        depth = np.frombuffer(depth_fbo.read(components=1, attachment=-1, dtype="f4"), np.float32)
        covered = depth.reshape(h, w) < 1.0
        self._row_work = (covered * multipliers[::-1]).sum(axis=1, dtype=np.float64)

    def rows_within(self, seconds: float) -> int:
        """Rows from :attr:`band_start` whose predicted cost fits ``seconds`` (at least 1)."""
        counts = self._row_work[self.band_start :]
        if self._pixel_cost_s is None:  # nothing measured yet: one row, or up to the first pixels
            return max(1, int(np.argmax(counts > 0))) if counts.any() else len(counts)
        cost = np.cumsum(counts) * self._pixel_cost_s
        return max(1, int(np.searchsorted(cost, seconds, side="right")))

    def measure_band(self, rows: int, seconds: float) -> None:
        """Learn the cost per unit of work from a band of ``rows`` rows at :attr:`band_start`
        that took ``seconds`` (GPU finished)."""
        work = float(self._row_work[self.band_start : self.band_start + rows].sum())
        if work > 0:
            self._pixel_cost_s = seconds / work

    def preview_target(self, size: tuple[int, int]) -> tuple[moderngl.Framebuffer, tuple[int, int]]:
        """The first pass's target for an image of ``size`` (w, h): colour and depth at
        1/:data:`PREVIEW_SCALE` of it, and that size."""
        preview_size = (max(1, size[0] // PREVIEW_SCALE), max(1, size[1] // PREVIEW_SCALE))
        if self._preview is None or self._preview.size != preview_size:
            self.release()
            self._preview = self.ctx.texture(preview_size, 4, dtype="f4")
            depth = self.ctx.depth_renderbuffer(preview_size)
            self._preview_fbo = self.ctx.framebuffer([self._preview], depth)
        return self._preview_fbo, preview_size

    def bind_first_pass(self, program: moderngl.Program, batch: moderngl.Texture) -> None:
        """Give the resolve ``program`` the running ``batch``'s rows and the preview elsewhere."""
        batch.use(location=1)
        self._preview.use(location=2)
        set_uniform(program, "u_batch", 1)
        set_uniform(program, "u_preview", 2)
        set_uniform(program, "u_preview_scale", PREVIEW_SCALE)

    def release(self) -> None:
        """Free the preview; safe to call twice."""
        if self._preview_fbo is not None:
            for obj in (*self._preview_fbo.color_attachments, self._preview_fbo.depth_attachment):
                obj.release()
            self._preview_fbo.release()
        self._preview = self._preview_fbo = None
