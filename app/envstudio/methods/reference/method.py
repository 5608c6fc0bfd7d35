"""Method ``reference``: the rendering equation (seed 000 eq. 1) integrated per pixel.

A progressive GPU estimator: every frame adds one batch of ``samples``
multiple-importance-sampled estimates per reflector pixel (cosine / Phong /
GGX lobe sampling combined with environment sampling by luminance, balance
heuristic), accumulated with additive blending in float targets together with
the squares of the batch means, so each pixel carries its own standard error.

Samples come from one Owen-scrambled Sobol sequence per pixel continued
across batches (``sequence=sobol``, randomised quasi-Monte Carlo: errors fall
faster than 1/sqrt(n)) or from independent batches (``sequence=random``, whose
batch-mean spread is an exact standard error; under ``sobol`` it overstates
the error).

With ``adaptive`` on, every pixel's share of each batch follows its own
error: at every doubling from :data:`ADAPT_FROM_BATCHES` on, pixel i draws
m_i × ``samples`` estimates per batch, m_i ∝ its standard deviation (Neyman
allocation, methods/reference/sample_allocation.py). Each batch mean keeps weight 1, and
each pixel's Sobol sequence continues at its own count.

Convergence is judged by the successive-half criterion: four times per
doubling of the batch count n (:func:`is_checkpoint`) the estimate I_n is
compared with I_{n/2}; the reference is converged when RMS(I_n − I_{n/2}) /
RMS(I_n) over the reflector pixels falls below ``tolerance`` (0.1 % by
default). It also stops on its sample budget (``max_samples``) or its time
budget (``time_limit`` seconds, 0: none), both reported as not converged, and
its status line shows the noise reached: the median relative standard error
over the reflector (:meth:`ReferenceMethod.relative_standard_error`), the
quantity ``compare`` stops on by default. The accumulation restarts whenever the
camera, the parameters, the environment, the transforms or the size change;
the parameters that only decide when to stop and how a batch is split into
draws (:data:`SCHEDULING_PARAMETERS`) do not restart it: a larger budget or a
lower tolerance continues where the run stopped.

The parts, each in its module of methods/reference/: the parameters
(parameters.py), the estimator program (estimator.py), the GPU sums
(accumulation.py) and what they say (batch_statistics.py), convergence
(convergence.py), the saved accumulation (saved_state.py) and the window's
banded and preview passes (window_passes.py).

Shaders: shaders/reference/accumulate.glsl (estimator), sampling.glsl,
radiance.glsl, resolve.glsl.
"""

from __future__ import annotations

import time

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.gpu.shader_source import preprocess
from envstudio.methods.reference import saved_state
from envstudio.methods.reference.accumulation import Accumulation
from envstudio.methods.reference.convergence import Convergence
from envstudio.methods.reference.estimator import Estimator, adding
from envstudio.methods.reference.parameters import (
    MODELS,
    REFERENCE_PARAMETERS,
    SCHEDULING_PARAMETERS,
)
from envstudio.methods.reference.window_passes import PREVIEW_SAMPLES, WindowPasses
from envstudio.plugin import (
    ConvergenceStatus,
    FrameInputs,
    GpuScene,
    Method,
    PairedEstimates,
    is_checkpoint,
    read_shader,
    set_uniform,
)
from envstudio.scene.tangents import TangentField
from envstudio.shading.tangent_buffers import TangentBuffers

ADAPT_FROM_BATCHES = 8
#: The reference's programs: the estimator, the batch merge, and the depth prepass
#: (which picks the pixels that get samples).
ESTIMATE_PROGRAMS = (
    "reference/accumulate.glsl",
    "reference/merge_batch.glsl",
    "reference/resolve.glsl",
)


class ReferenceMethod(Method):
    """Ground truth by progressive Monte Carlo integration of the rendering equation.

    Each frame prepares the estimator for the scene, restarts the
    accumulation where what it estimates changed, adds samples (a batch, or
    bands of one within :attr:`frame_budget_ms`) and resolves the mean onto
    the reflectors. Every pass draws the reflectors through
    :meth:`_draw_reflectors`.
    """

    name = "reference"
    paper = "Monte Carlo ground truth (seed 000 eq. 1)"
    #: The reflectance models it renders (``model``): a reference for methods of each.
    models = MODELS
    title = "Reference (Monte Carlo)"
    summary = "Rendering equation per pixel by MIS importance sampling, accumulated to convergence."
    progressive = True
    parameters = REFERENCE_PARAMETERS

    def __init__(self, ctx, programs):
        super().__init__(ctx, programs)
        self._estimator = Estimator(ctx, programs, self.values)
        self._accumulation = Accumulation(ctx)
        self._convergence = Convergence(self.values)
        self._window = WindowPasses(ctx)
        self._tangent_buffers = TangentBuffers(ctx)
        self._key: tuple | None = None  # what the accumulation estimates (restarts on change)
        self._pending_state: saved_state.SavedState | None = None

    @property
    def status(self) -> ConvergenceStatus:
        """Batches, samples per pixel, checks and the verdict of the current accumulation."""
        return self._convergence.status

    def finished(self) -> bool:
        """Converged, the sample budget spent, or the time limit reached."""
        return self.stop_reason() is not None

    def stop_reason(self) -> str | None:
        """Why the accumulation stops: ``converged``, ``max_samples`` or ``time_limit``; None.

        See :meth:`Convergence.stop_reason`.
        """
        return self._convergence.stop_reason()

    def status_line(self) -> str:
        """Samples, noise, the last half-change, the state, and the projected time left; while
        the window's first batch runs, how far it is."""
        size = self._accumulation.size
        if size is not None and self._window.showing_first_pass(self.status.batches):
            done = self._window.first_pass_progress(size[1])
            return f"first pass {100 * done:.0f} % (coarse preview elsewhere)"
        if size is not None:
            self._convergence.refresh_noise(self._accumulation.noise)
        return self._convergence.describe()

    def traces_anything(self) -> bool:
        """Whether tracing can change the estimate with the current values: ``trace`` on, and
        not the Banks model without self-shadowing and without a diffuse term, whose lobe
        reads the environment from every side of the surface (accumulate.glsl's
        ``sample_banks``: such directions are never traced)."""
        if not self.values["trace"]:
            return False
        values = self.values
        untraced_lobe = values["model"] == "banks" and not values["self_shadowing"]
        return not (untraced_lobe and not np.any(values["kd"]))

    def relative_standard_error(self) -> float:
        """The noise: median relative standard error over the reflector now.

        Returns
        -------
        float
            :func:`~batch_statistics.median_relative_error` of the estimate
            and its standard error over the covered pixels; inf before two batches (no spread
            yet). Under ``sequence=sobol`` an upper bound.
        """
        if self._accumulation.size is None or self.status.batches < 2:
            return float("inf")
        return self._accumulation.noise()

    # -- rendering ---------------------------------------------------------------------------

    def render(self, frame: FrameInputs) -> None:
        self._prepare(frame.scene, frame)
        if not self.finished():
            with frame.timer.measure("reference.accumulate"):
                self._accumulate(frame)
        frame.target.use()
        with frame.timer.measure("reference.resolve"):
            program = self.programs.get("reference/resolve.glsl")
            self._accumulation.sum.use(location=0)
            set_uniform(program, "u_sum", 0)
            first_pass = self._window.showing_first_pass(self.status.batches)
            set_uniform(program, "u_first_pass", first_pass)
            if first_pass:  # rows of the running batch, and the coarse pass elsewhere
                self._window.bind_first_pass(program, self._accumulation.batch)
            self._draw_reflectors(program, frame)

    def _prepare(self, scene: GpuScene, frame: FrameInputs) -> None:
        """Ready the estimator for ``scene``; restart (or resume) where the estimate changed."""
        self._estimator.prepare(scene)
        key = (
            frame.size,
            frame.view.tobytes(),
            frame.projection.tobytes(),
            tuple(v for k, v in self.values.as_dict().items() if k not in SCHEDULING_PARAMETERS),
            scene.environment_revision,
            scene.geometry_revision,
        )
        if key != self._key:
            self._key = key
            self._accumulation.ensure(frame.size, self._estimator.shares_untraced())
            self._accumulation.clear()
            self._convergence.restart()
            self._window.restart()
            if self._pending_state is not None:
                saved_state.restore(
                    self._pending_state,
                    self._accumulation,
                    self._convergence,
                    int(self.values["samples"]),
                )
                self._pending_state = None
        self._convergence.judge()  # the tolerance may have changed

    def _accumulate(self, frame: FrameInputs) -> None:
        """Add samples: one whole batch, or bands of rows within :attr:`frame_budget_ms`
        (methods/reference/window_passes.py)."""
        height = frame.size[1]
        window = self._window
        start = time.perf_counter()
        while True:
            if window.band_start == 0:
                if self.frame_budget_ms is not None and not window.preview_made:
                    self._preview_pass(frame)
                self._depth_prepass(frame)
            rows = height - window.band_start
            if self.frame_budget_ms is not None:
                rows = window.rows_within(0.5e-3 * self.frame_budget_ms)
            band_start = time.perf_counter()
            self._accumulate_band(frame, window.band_start, rows)
            if self.frame_budget_ms is not None:
                self.ctx.finish()
                window.measure_band(rows, time.perf_counter() - band_start)
            window.band_start += rows
            if window.band_start >= height:
                window.band_start = 0
                self._finish_batch()
                if self.frame_budget_ms is None or self.finished():
                    return
            if (time.perf_counter() - start) * 1e3 >= self.frame_budget_ms:
                return

    def _accumulate_band(self, frame: FrameInputs, first_row: int, rows: int) -> None:
        """Add this batch's estimates of ``rows`` rows from ``first_row`` (from the bottom),
        in draws of :meth:`Estimator.chunk_samples` each."""
        samples = int(self.values["samples"])
        program = self._estimator.program(
            frame, frame.size, samples, self.status.batches, self._accumulation
        )
        self._accumulation.batch_fbo.use()
        chunk = self._estimator.chunk_samples()
        largest = samples * int(self._accumulation.allocation.multipliers.max())
        with adding(self.ctx):
            self.ctx.scissor = (0, first_row, frame.size[0], rows)
            for first in range(0, largest, chunk):
                set_uniform(program, "u_chunk_first", first)
                set_uniform(program, "u_chunk_samples", chunk)
                self._draw_reflectors(program, frame)
            self.ctx.scissor = None

    def _preview_pass(self, frame: FrameInputs) -> None:
        """The window's first pass: the estimator at :data:`PREVIEW_SAMPLES` over every
        reflector pixel of a coarse image (the coarse pixel's footprint), shown until a batch
        reaches the pixel: no reflector stays black while the first batch runs."""
        fbo, size = self._window.preview_target(frame.size)
        self._draw_depth(fbo, frame)  # the viewport follows: the same projection, fewer pixels
        program = self._estimator.program(
            frame, size, PREVIEW_SAMPLES, self.status.batches, self._accumulation
        )
        set_uniform(program, "u_adaptive", False)
        set_uniform(program, "u_chunk_first", 0)
        set_uniform(program, "u_chunk_samples", PREVIEW_SAMPLES)
        fbo.use()
        with adding(self.ctx):
            self._draw_reflectors(program, frame)
        self._window.preview_made = True

    def _depth_prepass(self, frame: FrameInputs) -> None:
        """Nearest surface depth per pixel: only the visible reflector surface is shaded
        (:meth:`coverage` leaves hidden pixels out); with a frame budget, each row's work."""
        depth_fbo = self._accumulation.depth_fbo
        self._draw_depth(depth_fbo, frame)
        if self.frame_budget_ms is not None:
            multipliers = self._accumulation.allocation.multipliers
            self._window.count_row_work(depth_fbo, frame.size, multipliers)

    def _draw_depth(self, target: moderngl.Framebuffer, frame: FrameInputs) -> None:
        """Clear ``target`` and draw the nearest surface's depth into it: the reflectors and
        the local objects, so reflector pixels hidden behind local objects get no samples."""
        target.clear(depth=1.0)
        target.use()
        self.ctx.enable(moderngl.DEPTH_TEST)
        program = self.programs.get("reference/resolve.glsl")
        self._draw_reflectors(program, frame)
        for gpu_node in frame.scene.local_objects():
            set_uniform(program, "u_model", gpu_node.model)
            set_uniform(program, "u_normal_matrix", gpu_node.normal)
            gpu_node.mesh.render(program)

    def _draw_reflectors(self, program: moderngl.Program, frame: FrameInputs) -> None:
        """Draw the scene's reflectors with ``program`` (with the tangents, model=banks)."""
        set_uniform(program, "u_view", frame.view)
        set_uniform(program, "u_projection", frame.projection)
        banks = self.values["model"] == "banks"
        field = TangentField(str(self.values["tangent_field"]), str(self.values["tangent_axis"]))
        reflectors = frame.scene.reflectors()
        if banks:
            self._tangent_buffers.forget_unused(reflectors)
        for gpu_node in reflectors:
            set_uniform(program, "u_model", gpu_node.model)
            set_uniform(program, "u_normal_matrix", gpu_node.normal)
            if banks:  # the tangents of the banks material (shading/tangent_buffers.py)
                self._tangent_buffers.render(program, gpu_node, field)
            else:
                gpu_node.mesh.render(program)

    def _finish_batch(self) -> None:
        """Merge the batch; check convergence at checkpoints, reallocate at doublings."""
        self._accumulation.add_batch(
            self.programs.compute("reference/merge_batch.glsl"),
            self.programs.compute("reference/merge_difference.glsl"),
        )
        status = self.status
        status.batches += 1
        batches = status.batches
        status.samples = self._accumulation.allocation.samples_per_pixel(
            batches, int(self.values["samples"])
        )
        if is_checkpoint(batches):
            self._convergence.check(self.estimate(), self.coverage())
        doubling = batches & (batches - 1) == 0
        if self.values["adaptive"] and doubling and batches >= ADAPT_FROM_BATCHES:
            self._accumulation.reallocate(batches)

    # -- results -----------------------------------------------------------------------------

    def estimate(self) -> npt.NDArray[np.float32]:
        """(h, w, 3) mean radiance of the accumulation, row 0 at the top (0 off the reflectors)."""
        return self._accumulation.estimate()

    def standard_error(self) -> npt.NDArray[np.float32]:
        """(h, w, 3) standard error of :meth:`estimate` from the spread of the batch means.

        With adaptive sampling the batches differ in size; the spread then
        estimates their mean variance, and the error of their mean is still
        its square root over the batch count.
        """
        return self._accumulation.standard_error()

    def untraced_estimate(self) -> npt.NDArray[np.float32] | None:
        """(h, w, 3) the untraced estimate from the same samples (``untraced_too``), else None.

        The environment-map model the methods approximate: every sample's
        direction sees the environment, nothing blocks or reflects it.
        """
        return self._accumulation.untraced_estimate()

    def paired(self) -> PairedEstimates | None:
        """The traced and untraced estimates of the same samples (``untraced_too``), with
        their errors and their difference's, else None: what a control variate needs."""
        return self._accumulation.paired()

    def untraced_relative_standard_error(self) -> float:
        """The untraced estimate's noise, as :meth:`relative_standard_error` (inf without one)."""
        if self.status.batches < 2:
            return float("inf")
        return self._accumulation.untraced_noise()

    def coverage(self) -> npt.NDArray[np.bool_]:
        """(h, w) True where the reflectors have samples."""
        return self._accumulation.coverage()

    # -- saving and resuming ----------------------------------------------------------------

    def accumulation_state(self) -> dict[str, npt.NDArray]:
        """The accumulation as arrays, for :meth:`resume` (measure/ground_truth_cache.py).

        Keys and shapes: methods/reference/saved_state.py.
        """
        return saved_state.accumulation_state(self._accumulation, self._convergence)

    def resume(self, state: dict[str, npt.NDArray]) -> None:
        """Continue from ``state`` at the next frame, as if its batches had been rendered.

        The caller vouches that ``state`` was accumulated with the same scene,
        view, size and parameters (measure/ground_truth_cache.py keys it so); a
        state of another size is ignored. The sample sequence continues at the
        saved batch count, so the resumed estimate equals an uninterrupted one.
        """
        self._pending_state = state
        self._key = None

    def saved_samples(self, state: dict[str, npt.NDArray]) -> int:
        """Samples per pixel a saved :meth:`accumulation_state` holds."""
        return saved_state.saved_samples(state, int(self.values["samples"]))

    def cache_identity(self) -> list[bytes]:
        """What the estimate depends on besides scene, camera and size, for the cache's key:
        the parameters but :data:`SCHEDULING_PARAMETERS`, then every shader file of
        :data:`ESTIMATE_PROGRAMS` (name and text)."""
        values = {k: v for k, v in self.values.as_dict().items() if k not in SCHEDULING_PARAMETERS}
        parts = [repr(sorted(values.items())).encode()]
        for name in estimate_shader_files():
            parts += [name.encode(), read_shader(name).encode()]
        return parts

    def release(self) -> None:
        """Free targets, sampling tables and tangent buffers; safe to call twice."""
        self._window.release()
        self._accumulation.release()
        self._tangent_buffers.release()
        self._estimator.release()
        self._key = None


def estimate_shader_files() -> list[str]:
    """Files (relative to the shader root) of :data:`ESTIMATE_PROGRAMS` and all they include."""
    files: list[str] = []
    for program in ESTIMATE_PROGRAMS:
        _, source_map = preprocess(program, "COMPUTE_SHADER", read_shader)
        files += [name for name in source_map.files if name not in files]
    return sorted(files)
