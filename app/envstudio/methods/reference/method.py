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

Shaders: shaders/reference/accumulate.glsl (estimator), sampling.glsl,
radiance.glsl, resolve.glsl.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator
from dataclasses import replace

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.env_sampling import LUMINANCE, EnvironmentDistribution
from envstudio.gpu.context import is_software_renderer, require_version
from envstudio.gpu.shader_source import preprocess
from envstudio.methods.reference.sample_allocation import (
    MAX_MULTIPLIER,
    SOFTWARE_SAMPLES_PER_BATCH,
    SampleAllocation,
)
from envstudio.methods.reference.tracing import TraceData
from envstudio.plugin import (
    MAX_TIME_LIMIT_S,
    ConvergenceStatus,
    FrameInputs,
    GpuScene,
    Method,
    Parameter,
    duration,
    fresnel_parameter,
    is_checkpoint,
    kd_parameter,
    project_convergence,
    read_shader,
    set_uniform,
)
from envstudio.scene.tangents import TangentField
from envstudio.shading.materials import BANKS_MATERIAL_PARAMETERS
from envstudio.shading.tangent_buffers import TangentBuffers

MODELS = ("phong", "microfacet", "banks")
SEQUENCES = ("random", "sobol")
ENVIRONMENT_SAMPLING = ("auto", "global", "lobe")
ADAPT_FROM_BATCHES = 8
#: Parameters that decide when to stop and how a batch is split into draws, not
#: what is estimated: changing one continues the accumulation, and the saved
#: accumulations' keys leave them out (measure/ground_truth_cache.py).
SCHEDULING_PARAMETERS = ("max_samples", "tolerance", "time_limit", "samples_per_draw")
#: The reference's programs: the estimator, the batch merge, and the depth prepass
#: (which picks the pixels that get samples).
ESTIMATE_PROGRAMS = (
    "reference/accumulate.glsl",
    "reference/merge_batch.glsl",
    "reference/resolve.glsl",
)
#: Seconds between measurements of the noise shown in the status line (a GPU read each).
NOISE_REFRESH_S = 2.0
#: The window's first pass: PREVIEW_SAMPLES per pixel at 1/PREVIEW_SCALE of the image's width
#: and height (1/16 of a default batch's work), so few of its pixels are a zero draw.
PREVIEW_SCALE = 4
PREVIEW_SAMPLES = 8
#: Batches before the time limit may stop the accumulation (a standard error needs two).
MIN_TIMED_BATCHES = 2


class _EnvironmentTables:
    """GPU copies of the luminance-sampling tables of one environment."""

    def __init__(self, ctx: moderngl.Context, radiance: npt.NDArray[np.float32]):
        dist = EnvironmentDistribution.from_latlong(radiance)
        h, w = dist.shape
        p_uv = dist.weights / dist.weights.sum() * (w * h)
        self.textures = [
            _r32f(ctx, dist.marginal_cdf[None, :]),
            _r32f(ctx, dist.conditional_cdf),
            _r32f(ctx, p_uv),
        ]

    def bind(self, program: moderngl.Program, first_unit: int) -> None:
        for offset, (name, tex) in enumerate(
            zip(("u_env_marginal", "u_env_conditional", "u_env_pdf_uv"), self.textures, strict=True)
        ):
            tex.use(location=first_unit + offset)
            set_uniform(program, name, first_unit + offset)

    def release(self) -> None:
        for tex in self.textures:
            tex.release()
        self.textures = []


def _r32f(ctx: moderngl.Context, array: npt.ArrayLike) -> moderngl.Texture:
    data = np.ascontiguousarray(array, dtype=np.float32)
    tex = ctx.texture((data.shape[1], data.shape[0]), 1, data.tobytes(), dtype="f4")
    tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return tex


class ReferenceMethod(Method):
    """Ground truth by progressive Monte Carlo integration of the rendering equation."""

    name = "reference"
    paper = "Monte Carlo ground truth (seed 000 eq. 1)"
    #: The reflectance models it renders (``model``): a reference for methods of each.
    models = MODELS
    title = "Reference (Monte Carlo)"
    summary = "Rendering equation per pixel by MIS importance sampling, accumulated to convergence."
    progressive = True
    parameters = (
        Parameter(
            "model",
            "choice",
            "phong",
            choices=MODELS,
            rebuild=False,
            help="phong: seed 000 eq. 8 (diffuse + Phong, Schlick); microfacet: GGX; banks: "
            "seed 004 §5.3's Banks lobe about the tangent field (diffuse + Banks, Schlick).",
        ),
        *(replace(p, applies_when={"model": "banks"}) for p in BANKS_MATERIAL_PARAMETERS),
        Parameter(
            "self_shadowing",
            "bool",
            False,
            help="model=banks: keep the term ⟨n,l⟩ (and the hemisphere) that method banks "
            "drops (seed 004 §5.3); off: the whole sphere, as the 3D map.",
            applies_when={"model": "banks"},
        ),
        fresnel_parameter(1.0, "Schlick reflectance at normal incidence, per RGB channel."),
        kd_parameter(0.0, "Diffuse albedo, per RGB channel."),
        Parameter(
            "phong_exponent",
            "float",
            200.0,
            0.01,
            1_000_000.0,
            "N",
            "Phong exponent (microfacet: alpha = sqrt(2 / (4N + 2)); N < 1 reaches alpha 0.58 … "
            "0.995).",
            log=True,
            applies_when={"model": ("phong", "microfacet")},
        ),
        Parameter(
            "trace",
            "bool",
            True,
            rebuild=True,
            help="Trace the scene's triangles: self-occlusion, local and self-reflections.",
        ),
        Parameter(
            "untraced_too",
            "bool",
            False,
            rebuild=True,
            help="With trace: also accumulate the untraced estimate (the environment-map model) "
            "from the same samples (with trace only): compare's approximation error at no "
            "second run.",
        ),
        Parameter(
            "pixel_filter",
            "bool",
            True,
            help="Average each pixel's footprint (anti-aliased, as mip-mapped methods see it); "
            "off: the pixel centre only.",
        ),
        Parameter(
            "sequence",
            "choice",
            "sobol",
            choices=SEQUENCES,
            help="sobol: one scrambled Sobol sequence per pixel (faster convergence; the "
            "standard error shown is then an upper bound); random: independent batches.",
        ),
        Parameter(
            "environment_sampling",
            "choice",
            "auto",
            choices=ENVIRONMENT_SAMPLING,
            help="lobe: draw the glossy term's environment samples by luminance inside the "
            "lobe's cap (small lamps converge faster); global: from the whole map (better where "
            "local objects hide the environment); auto: global when tracing a scene with local "
            "objects, else lobe.",
        ),
        Parameter(
            "samples", "int", 8, 1, 256, "spp/frame", "Estimates per pixel added each frame."
        ),
        Parameter(
            "adaptive",
            "bool",
            True,
            help="At every doubling, give each pixel 1-4 x `samples` per frame in proportion to "
            "its standard error (more where the image is noisy).",
        ),
        Parameter(
            "samples_per_draw",
            "int",
            0,
            0,
            256 * MAX_MULTIPLIER,
            "spp",
            "Estimates a pixel adds per draw call; a batch takes as many draws as it needs. "
            "0: the whole batch in one draw on GPUs, 32 on software renderers (their loop limit, "
            "which also caps other values). Smaller chunks keep more draws in flight on a GPU; "
            "the samples are the same.",
        ),
        Parameter(
            "max_samples",
            "int",
            8192,
            1,
            10_000_000,
            "spp",
            "Sample budget per pixel; beyond it the result is reported as not converged.",
        ),
        Parameter(
            "tolerance",
            "float",
            0.001,
            1e-5,
            0.1,
            "",
            "Converged when the successive-half RMS change is below this.",
            log=True,
        ),
        Parameter(
            "time_limit",
            "float",
            0.0,
            0.0,
            MAX_TIME_LIMIT_S,
            "s",
            "Time budget: stop accumulating this many seconds after the (re)start, reported as "
            "not converged unless it converged first (0: no limit).",
            log=True,
        ),
    )

    def __init__(self, ctx, programs):
        super().__init__(ctx, programs)
        self.status = ConvergenceStatus()
        self._tables: _EnvironmentTables | None = None
        self._tables_revision = -1
        self._trace: TraceData | None = None
        self._trace_key: tuple | None = None
        self._sum: moderngl.Texture | None = None
        self._sum_sq: moderngl.Texture | None = None
        self._sums_fbo: moderngl.Framebuffer | None = None
        self._batch: moderngl.Texture | None = None  # this batch's sums and counts
        # with untraced_too: the untraced estimate's batch and sums, from the same samples
        self._untraced: tuple[moderngl.Texture, moderngl.Texture, moderngl.Texture] | None = None
        self._depth: moderngl.Renderbuffer | None = None
        self._batch_fbo: moderngl.Framebuffer | None = None
        self._depth_fbo: moderngl.Framebuffer | None = None
        self._key: tuple | None = None
        # estimates at earlier checkpoints, by batch count, until no check needs them
        self._snapshots: dict[int, npt.NDArray[np.float32]] = {}
        self._pending_state: dict[str, npt.NDArray] | None = None
        self._band_start = 0
        # the window's first pass: a few samples per pixel at 1/PREVIEW_SCALE of the size, shown
        # where no batch has reached yet (made once per restart, only with a frame budget)
        self._preview: moderngl.Texture | None = None
        self._preview_fbo: moderngl.Framebuffer | None = None
        self._preview_made = False
        self._row_work: npt.NDArray[np.float64] | None = None
        self._pixel_cost_s: float | None = None
        self._allocation: moderngl.Texture | None = None  # (units, m) per pixel, for the shader
        self._sample_allocation = SampleAllocation.plain((1, 1))
        self._tangent_buffers = TangentBuffers(ctx)

    def finished(self) -> bool:
        """Converged, the sample budget spent, or the time limit reached."""
        return self.stop_reason() is not None

    def stop_reason(self) -> str | None:
        """Why the accumulation stops: ``converged``, ``max_samples`` or ``time_limit``; None.

        The time limit (``time_limit`` > 0) counts from this process's
        (re)start of the accumulation (:meth:`ConvergenceStatus.run_elapsed`)
        and ends it only once :data:`MIN_TIMED_BATCHES` batches give a
        standard error.
        """
        status = self.status
        if status.converged:
            return "converged"
        if status.samples >= int(self.values["max_samples"]):
            return "max_samples"
        limit = float(self.values["time_limit"])
        if limit > 0 and status.batches >= MIN_TIMED_BATCHES and status.run_elapsed() >= limit:
            return "time_limit"
        return None

    def status_line(self) -> str:
        """Samples, noise, the last half-change, the state, and the projected time left; while
        the window's first batch runs, how far it is."""
        if self.status.batches == 0 and self._preview_made and self._sum is not None:
            done = self._band_start / max(self._sum.size[1], 1)
            return f"first pass {100 * done:.0f} % (coarse preview elsewhere)"
        self._refresh_noise()
        line = self.status.describe()
        reason = self.stop_reason()
        if reason == "converged":
            return line
        if reason == "max_samples":
            return line + " (budget spent: NOT converged)"
        limit = float(self.values["time_limit"])
        if reason == "time_limit":
            return line + f" (time limit {limit:g} s reached: NOT converged)"
        projection = project_convergence(self.status.checks, float(self.values["tolerance"]))
        if limit > 0:
            line += f", time limit in {duration(limit - self.status.run_elapsed())}"
        if projection is not None:
            line += f", ≈ {duration(projection['seconds'] - self.status.elapsed())} to go"
        return line

    def relative_standard_error(self) -> float:
        """The noise: median relative standard error over the reflector now.

        Returns
        -------
        float
            :func:`median_relative_error` of the estimate and its standard
            error over the covered pixels; inf before two batches (no spread
            yet). Under ``sequence=sobol`` an upper bound.
        """
        if self._sum is None or self.status.batches < 2:
            return float("inf")
        total, squares = self._read()
        count = np.maximum(total[..., 3:], 1.0)
        error = np.sqrt(_batch_variance(total, squares) / count)
        return median_relative_error(total[..., :3] / count, error, total[..., 3] > 0)

    def _refresh_noise(self) -> None:
        """Measure the noise for the status line: new samples, and stopped or its interval due."""
        status = self.status
        if self._sum is None or status.samples == status.noise_samples:
            return
        if not self.finished() and time.perf_counter() - status.noise_at < NOISE_REFRESH_S:
            return
        status.noise = self.relative_standard_error()
        status.noise_samples = status.samples
        status.noise_at = time.perf_counter()

    # -- rendering ---------------------------------------------------------------------------

    def render(self, frame: FrameInputs) -> None:
        scene = frame.scene
        self._prepare(scene, frame)
        if not self.finished():
            with frame.timer.measure("reference.accumulate"):
                self._accumulate(frame)
        frame.target.use()
        with frame.timer.measure("reference.resolve"):
            program = self.programs.get("reference/resolve.glsl")
            self._sum.use(location=0)
            set_uniform(program, "u_sum", 0)
            first_pass = self.status.batches == 0 and self._preview_made
            set_uniform(program, "u_first_pass", first_pass)
            if first_pass:  # rows of the running batch, and the coarse pass elsewhere
                self._batch.use(location=1)
                self._preview.use(location=2)
                set_uniform(program, "u_batch", 1)
                set_uniform(program, "u_preview", 2)
                set_uniform(program, "u_preview_scale", PREVIEW_SCALE)
            self._draw_reflectors(program, frame)

    def _accumulate(self, frame: FrameInputs) -> None:
        """Add samples: one whole batch, or bands of rows within :attr:`frame_budget_ms`.

        In the window a batch over the whole image can take seconds on a
        software renderer; the image is then processed in horizontal bands,
        as many per frame as fit the budget, so the UI stays responsive. A
        batch is complete when the bands have covered every row. The cost of a
        band is predicted from the reflector pixels in its rows (counted in the
        depth prepass) times the last measured cost per pixel, so rows of
        background cost nothing and a band never grows past the reflector's
        edge into seconds of work.
        """
        height = frame.size[1]
        start = time.perf_counter()
        while True:
            if self._band_start == 0:
                if self.frame_budget_ms is not None and not self._preview_made:
                    self._preview_pass(frame)
                self._depth_prepass(frame)
            rows = height - self._band_start
            if self.frame_budget_ms is not None:
                rows = self._rows_within(0.5e-3 * self.frame_budget_ms)
            band_start = time.perf_counter()
            self._accumulate_band(frame, self._band_start, rows)
            if self.frame_budget_ms is not None:
                self.ctx.finish()
                work = float(self._row_work[self._band_start : self._band_start + rows].sum())
                if work > 0:
                    self._pixel_cost_s = (time.perf_counter() - band_start) / work
            self._band_start += rows
            if self._band_start >= height:
                self._band_start = 0
                self._finish_batch()
                if self.frame_budget_ms is None or self.finished():
                    return
            if (time.perf_counter() - start) * 1e3 >= self.frame_budget_ms:
                return

    def _rows_within(self, seconds: float) -> int:
        """Rows from the current band start whose predicted cost fits ``seconds`` (at least 1)."""
        counts = self._row_work[self._band_start :]
        if self._pixel_cost_s is None:  # nothing measured yet: one row, or up to the first pixels
            return max(1, int(np.argmax(counts > 0))) if counts.any() else len(counts)
        cost = np.cumsum(counts) * self._pixel_cost_s
        return max(1, int(np.searchsorted(cost, seconds, side="right")))

    def _finish_batch(self) -> None:
        self._merge_batch()
        self.status.batches += 1
        self.status.samples = self._mean_samples()
        batches = self.status.batches
        if is_checkpoint(batches):
            self._check_convergence()
        doubling = batches & (batches - 1) == 0
        if self.values["adaptive"] and doubling and batches >= ADAPT_FROM_BATCHES:
            self._reallocate()

    def _prepare(self, scene: GpuScene, frame: FrameInputs) -> None:
        if self._tables_revision != scene.environment_revision:
            if self._tables is not None:
                self._tables.release()
            self._tables = _EnvironmentTables(self.ctx, scene.scene.environment.radiance)
            self._tables_revision = scene.environment_revision
        geometry = (id(scene), scene.geometry_revision)
        if self._uses_bvh() and geometry != self._trace_key:
            if self._trace is not None:
                self._trace.release()
            self._trace = TraceData(self.ctx, scene)
            self._trace_key = geometry
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
            self._ensure_targets(frame.size)
            self._sums_fbo.clear(0.0, 0.0, 0.0, 0.0)
            self._batch_fbo.clear(0.0, 0.0, 0.0, 0.0)
            for tex in (self._untraced or ())[1:]:
                tex.write(np.zeros((*frame.size[::-1], 4), np.float32).tobytes())
            self.status = ConvergenceStatus()
            self._set_allocation(SampleAllocation.plain((frame.size[1], frame.size[0])))
            self._snapshots = {}
            self._band_start = 0
            self._preview_made = False
            if self._pending_state is not None:
                self._restore(self._pending_state, frame.size)
                self._pending_state = None
        self._judge_convergence()  # the tolerance may have changed

    def _depth_prepass(self, frame: FrameInputs) -> None:
        """Nearest surface depth per pixel: only the visible reflector surface is shaded.

        With additive blending every fragment passing a plain depth test would
        count, so the accumulation tests ``<=`` against this depth. Local objects
        are included so reflector pixels hidden behind them get no samples
        (and :meth:`coverage` leaves them out).
        """
        self._depth_fbo.clear(depth=1.0)
        self._depth_fbo.use()
        self._draw_depth(frame)
        if self.frame_budget_ms is not None:
            w, h = frame.size
            depth = np.frombuffer(
                self._depth_fbo.read(components=1, attachment=-1, dtype="f4"), np.float32
            )
            # pixels per row (from the bottom) weighted by their samples per batch
            covered = depth.reshape(h, w) < 1.0
            multipliers = self._sample_allocation.multipliers[::-1]
            self._row_work = (covered * multipliers).sum(axis=1, dtype=np.float64)

    def _draw_depth(self, frame: FrameInputs) -> None:
        """Reflectors and local objects into the bound target's depth (the nearest surface)."""
        self.ctx.enable(moderngl.DEPTH_TEST)
        program = self.programs.get("reference/resolve.glsl")
        self._draw_reflectors(program, frame)
        for gpu_node in frame.scene.local_objects():
            set_uniform(program, "u_model", gpu_node.model)
            set_uniform(program, "u_normal_matrix", gpu_node.normal)
            gpu_node.mesh.render(program)

    @contextlib.contextmanager
    def _adding(self) -> Iterator[None]:
        """Additive blending onto the nearest surface (depth ``<=``): how estimates accumulate."""
        self.ctx.enable(moderngl.DEPTH_TEST | moderngl.BLEND)
        self.ctx.depth_func = "<="
        self.ctx.blend_func = moderngl.ONE, moderngl.ONE
        self.ctx.blend_equation = moderngl.FUNC_ADD
        try:
            yield
        finally:
            self.ctx.disable(moderngl.BLEND)
            self.ctx.blend_func = moderngl.DEFAULT_BLENDING
            self.ctx.depth_func = "<"

    def _shares_untraced(self) -> bool:
        """Whether each batch also gives the untraced estimate (``untraced_too`` with tracing)."""
        return bool(self.values["trace"] and self.values["untraced_too"])

    def _uses_bvh(self) -> bool:
        """Whether the scene's triangles are traced: for local light or for the pixel footprint."""
        return bool(self.values["trace"] or self.values["pixel_filter"])

    def _accumulate_band(self, frame: FrameInputs, first_row: int, rows: int) -> None:
        program = self._accumulate_program(frame, frame.size, int(self.values["samples"]))
        self._batch_fbo.use()
        chunk = self._chunk_samples()
        largest = int(self.values["samples"]) * int(self._sample_allocation.multipliers.max())
        with self._adding():
            self.ctx.scissor = (0, first_row, frame.size[0], rows)
            for first in range(0, largest, chunk):
                set_uniform(program, "u_chunk_first", first)
                set_uniform(program, "u_chunk_samples", chunk)
                self._draw_reflectors(program, frame)
            self.ctx.scissor = None

    def _preview_pass(self, frame: FrameInputs) -> None:
        """The window's first pass: every reflector pixel of a 1/:data:`PREVIEW_SCALE` image
        at :data:`PREVIEW_SAMPLES` (the estimator itself, the coarse pixel's footprint), shown
        until a batch reaches the pixel: no reflector stays black while the first batch runs."""
        size = (max(1, frame.size[0] // PREVIEW_SCALE), max(1, frame.size[1] // PREVIEW_SCALE))
        if self._preview is None or self._preview.size != size:
            self._release_preview()
            self._preview = self.ctx.texture(size, 4, dtype="f4")
            depth = self.ctx.depth_renderbuffer(size)
            self._preview_fbo = self.ctx.framebuffer([self._preview], depth)
        fbo = self._preview_fbo
        fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        fbo.use()  # the viewport follows: the same projection over fewer pixels
        self._draw_depth(frame)
        program = self._accumulate_program(frame, size, PREVIEW_SAMPLES)
        set_uniform(program, "u_adaptive", False)
        set_uniform(program, "u_chunk_first", 0)
        set_uniform(program, "u_chunk_samples", PREVIEW_SAMPLES)
        fbo.use()
        with self._adding():
            self._draw_reflectors(program, frame)
        self._preview_made = True

    def _accumulate_program(
        self, frame: FrameInputs, size: tuple[int, int], samples: int
    ) -> moderngl.Program:
        """The estimator with this frame's uniforms, for a target of ``size`` at ``samples``."""
        trace = bool(self.values["trace"])
        require_version(self.ctx, 430, "method reference needs OpenGL 4.3 (storage buffers)")
        defines = {"TRACE_LOCAL": int(trace), "UNTRACED_TOO": int(self._shares_untraced())}
        if self._uses_bvh():
            defines["TRACE_STACK"] = self._trace.stack_size
        program = self.programs.get("reference/accumulate.glsl", defines)
        scene = frame.scene
        scene.latlong.use(location=0)
        set_uniform(program, "u_latlong", 0)
        self._tables.bind(program, 1)
        if self._uses_bvh():
            self._trace.bind(program)
        if trace:
            set_uniform(program, "u_sh9", scene.sh9)
        view_projection = frame.projection.astype(np.float64) @ frame.view.astype(np.float64)
        set_uniform(program, "u_inverse_view_projection", np.linalg.inv(view_projection))
        set_uniform(program, "u_viewport", np.asarray(size, np.float32))
        set_uniform(program, "u_camera_position", frame.camera_position)
        set_uniform(program, "u_brdf_model", MODELS.index(self.values["model"]))
        for name in ("kd", "fresnel"):  # linear RGB
            set_uniform(program, f"u_{name}", tuple(self.values[name]))
        for name in ("phong_exponent", "sharpness"):
            set_uniform(program, f"u_{name}", float(self.values[name]))
        set_uniform(program, "u_banks_normalize", bool(self.values["normalize"]))
        set_uniform(program, "u_self_shadowing", bool(self.values["self_shadowing"]))
        set_uniform(program, "u_samples", samples)
        set_uniform(program, "u_sequence", SEQUENCES.index(self.values["sequence"]))
        set_uniform(program, "u_pixel_filter", bool(self.values["pixel_filter"]))
        set_uniform(program, "u_environment_sampling", int(self._samples_inside_lobe(scene)))
        set_uniform(program, "u_frame", self.status.batches)
        set_uniform(program, "u_adaptive", bool(self.values["adaptive"]))
        since = self.status.batches - self._sample_allocation.at
        set_uniform(program, "u_batches_since_allocation", since)
        self._allocation.use(location=4)
        set_uniform(program, "u_allocation", 4)
        return program

    def _chunk_samples(self) -> int:
        """Estimates a pixel draws per draw call: ``samples_per_draw``, else the whole batch.

        llvmpipe silently ends an invocation's loops after 65 535 iterations in
        all (:data:`SOFTWARE_SAMPLES_PER_BATCH`), so there a chunk is at most
        that many samples. The batch target adds the chunks up.
        """
        chunk = int(self.values["samples_per_draw"]) or int(self.values["samples"]) * MAX_MULTIPLIER
        if is_software_renderer(self.ctx):
            return min(chunk, SOFTWARE_SAMPLES_PER_BATCH)
        return chunk

    def _merge_batch(self) -> None:
        """Add the finished batch's mean per pixel (and its square) to the sums; clear it.

        With ``untraced_too`` the untraced batch is merged into its own sums the same way.
        """
        program = self.programs.compute("reference/merge_batch.glsl")
        self.ctx.memory_barrier(moderngl.ALL_BARRIER_BITS)
        sets = [(self._batch, self._sum, self._sum_sq)]
        if self._untraced is not None:
            sets.append(self._untraced)
        w, h = self._sum.size
        for batch, total, squares in sets:
            batch.bind_to_image(0, read=True, write=False)
            total.bind_to_image(1, read=True, write=True)
            squares.bind_to_image(2, read=True, write=True)
            program.run((w + 7) // 8, (h + 7) // 8)
            self.ctx.memory_barrier(moderngl.ALL_BARRIER_BITS)
        self._batch_fbo.clear(0.0, 0.0, 0.0, 0.0)

    def _samples_inside_lobe(self, scene: GpuScene) -> bool:
        """Whether environment samples come from the lobe's cap (``environment_sampling``).

        ``auto`` picks the whole map when traced local objects stand between the
        reflector and the environment: samples inside the lobe then mostly hit
        them, and the lobe samples alone do better (room at 128², 256 spp:
        2.3× less variance × time with ``global``; studio: 1.75× with ``lobe``).
        """
        choice = self.values["environment_sampling"]
        if choice == "auto":
            return not (self.values["trace"] and any(scene.local_objects()))
        return choice == "lobe"

    def _draw_reflectors(self, program: moderngl.Program, frame: FrameInputs) -> None:
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

    # -- results -----------------------------------------------------------------------------

    def estimate(self) -> npt.NDArray[np.float32]:
        """(h, w, 3) mean radiance of the accumulation, row 0 at the top (0 off the reflectors)."""
        total, _ = self._read()
        count = np.maximum(total[..., 3:], 1.0)
        return total[..., :3] / count

    def standard_error(self) -> npt.NDArray[np.float32]:
        """(h, w, 3) standard error of :meth:`estimate` from the spread of the batch means.

        With adaptive sampling the batches differ in size; the spread then
        estimates their mean variance, and the error of their mean is still
        its square root over the batch count.
        """
        total, squares = self._read()
        return np.sqrt(_batch_variance(total, squares) / np.maximum(total[..., 3:], 1.0))

    def untraced_estimate(self) -> npt.NDArray[np.float32] | None:
        """(h, w, 3) the untraced estimate from the same samples (``untraced_too``), else None.

        The environment-map model the methods approximate: every sample's
        direction sees the environment, nothing blocks or reflects it.
        """
        if self._untraced is None:
            return None
        total = _read_texture(self._untraced[1])
        return total[..., :3] / np.maximum(total[..., 3:], 1.0)

    def untraced_relative_standard_error(self) -> float:
        """The untraced estimate's noise, as :meth:`relative_standard_error` (inf without one)."""
        if self._untraced is None or self.status.batches < 2:
            return float("inf")
        total, squares = (_read_texture(tex) for tex in self._untraced[1:])
        count = np.maximum(total[..., 3:], 1.0)
        error = np.sqrt(_batch_variance(total, squares) / count)
        return median_relative_error(total[..., :3] / count, error, total[..., 3] > 0)

    def coverage(self) -> npt.NDArray[np.bool_]:
        """(h, w) True where the reflectors have samples."""
        total, _ = self._read()
        return total[..., 3] > 0

    def _read(self) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        return _read_texture(self._sum), _read_texture(self._sum_sq)

    def _mean_samples(self) -> int:
        """Estimates per covered pixel so far (the multipliers are fixed between doublings)."""
        return self._sample_allocation.samples_per_pixel(
            self.status.batches, int(self.values["samples"])
        )

    def _reallocate(self) -> None:
        """Set each pixel's samples per batch from its standard deviation (Neyman, floored)."""
        total, squares = self._read()
        variance = np.nan_to_num(_batch_variance(total, squares), posinf=0.0).sum(-1)
        covered = total[..., 3] > 0
        self._set_allocation(
            self._sample_allocation.reallocate(self.status.batches, variance, covered)
        )

    def _set_allocation(self, allocation: SampleAllocation) -> None:
        """Use ``allocation`` from the next batch on; the shader gets (units, m) per pixel."""
        self._sample_allocation = allocation
        units, _ = allocation.at_batch(allocation.at)
        texels = np.dstack([units, allocation.multipliers]).astype(np.float32)[::-1]
        self._allocation.write(np.ascontiguousarray(texels).tobytes())

    def _check_convergence(self) -> None:
        """Keep this checkpoint's estimate; compare it with the one at half the batches."""
        batches = self.status.batches
        current = self.estimate()
        mask = self.coverage()
        half = self._snapshots.get(batches // 2) if batches % 2 == 0 else None
        if half is not None and mask.any():
            now = current[mask].astype(np.float64)
            diff = now - half[mask]
            norm = np.sqrt(np.mean(now**2))
            # an all-black estimate has not converged to anything: never call it converged
            change = float(np.sqrt(np.mean(diff**2)) / norm) if norm > 0 else float("inf")
            self.status.rms_change = change
            self.status.checked_samples = self.status.samples
            self.status.checks.append(
                {
                    "samples": self.status.samples,
                    "change": change,
                    "seconds": self.status.elapsed(),
                }
            )
            self._judge_convergence()
        # later checks compare with later halves
        self._snapshots = {b: e for b, e in self._snapshots.items() if b > batches // 2}
        self._snapshots[batches] = current

    def _judge_convergence(self) -> None:
        """Converged: the last check's change is below the current tolerance."""
        change = self.status.rms_change
        self.status.converged = change is not None and change < float(self.values["tolerance"])

    # -- saving and resuming ----------------------------------------------------------------

    def accumulation_state(self) -> dict[str, npt.NDArray]:
        """The accumulation as arrays, for :meth:`resume` (measure/ground_truth_cache.py).

        Keys: ``sum``, ``sum_sq`` ((h, w, 4) float32, row 0 at the top),
        ``batches``, ``checked_samples`` (int64), ``rms_change`` (float64, NaN
        before the first check), ``snapshots`` ((k, h, w, 3) float32 estimates
        at the checkpoints later checks compare with) and ``snapshot_batches``
        ((k,) int64, their batch counts), ``checks`` ((k, 3) float64:
        samples, change, seconds of every check), ``seconds`` (float64
        wall time spent accumulating, over all the runs that built it),
        and the sample allocation (:meth:`SampleAllocation.as_arrays`).
        """
        total, squares = self._read()
        change = self.status.rms_change
        checks = [[c["samples"], c["change"], c["seconds"]] for c in self.status.checks]
        return {
            "sum": total,
            "sum_sq": squares,
            "batches": np.int64(self.status.batches),
            "checked_samples": np.int64(self.status.checked_samples),
            "rms_change": np.float64(np.nan if change is None else change),
            "snapshots": np.asarray(list(self._snapshots.values()), np.float32).reshape(
                -1, *total.shape[:2], 3
            ),
            "snapshot_batches": np.asarray(list(self._snapshots), np.int64),
            "checks": np.asarray(checks, np.float64).reshape(-1, 3),
            "seconds": np.float64(self.status.elapsed()),
            **self._sample_allocation.as_arrays(),
            **(
                {
                    "untraced_sum": _read_texture(self._untraced[1]),
                    "untraced_sum_sq": _read_texture(self._untraced[2]),
                }
                if self._untraced is not None
                else {}
            ),
        }

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
        batches = int(state["batches"])
        allocation = SampleAllocation.from_arrays(state, state["sum"].shape[:2], batches)
        return allocation.samples_per_pixel(batches, int(self.values["samples"]))

    def cache_identity(self) -> list[bytes]:
        """What the estimate depends on besides scene, camera and size, for the cache's key:
        the parameters but :data:`SCHEDULING_PARAMETERS`, then every shader file of
        :data:`ESTIMATE_PROGRAMS` (name and text)."""
        values = {k: v for k, v in self.values.as_dict().items() if k not in SCHEDULING_PARAMETERS}
        parts = [repr(sorted(values.items())).encode()]
        for name in estimate_shader_files():
            parts += [name.encode(), read_shader(name).encode()]
        return parts

    def _restore(self, state: dict[str, npt.NDArray], size: tuple[int, int]) -> None:
        shape = (size[1], size[0], 4)
        if state["sum"].shape != shape or state["sum_sq"].shape != shape:
            return
        pairs = [(self._sum, "sum"), (self._sum_sq, "sum_sq")]
        if self._untraced is not None and "untraced_sum" in state:
            pairs += [(self._untraced[1], "untraced_sum"), (self._untraced[2], "untraced_sum_sq")]
        for tex, name in pairs:
            tex.write(np.ascontiguousarray(state[name][::-1], np.float32).tobytes())
        batches = int(state["batches"])
        change = float(state["rms_change"])
        self.status.batches = batches
        self._set_allocation(SampleAllocation.from_arrays(state, shape[:2], batches))
        self.status.samples = self._mean_samples()
        self.status.checked_samples = int(state["checked_samples"])
        if not np.isnan(change):
            self.status.rms_change = change
            self._judge_convergence()
        self._snapshots = _saved_snapshots(state, batches)
        checks = state.get("checks", np.zeros((0, 3)))
        self.status.checks = [
            {"samples": int(n), "change": float(change), "seconds": float(seconds)}
            for n, change, seconds in checks
        ]
        self.status.started = time.perf_counter() - float(state.get("seconds", 0.0))

    # -- resources ---------------------------------------------------------------------------

    def _ensure_targets(self, size: tuple[int, int]) -> None:
        shared = self._shares_untraced()
        if (
            self._sum is not None
            and self._sum.size == tuple(size)
            and (self._untraced is not None) == shared
        ):
            return
        self._release_targets()
        self._sum = self.ctx.texture(size, 4, dtype="f4")
        self._sum_sq = self.ctx.texture(size, 4, dtype="f4")
        self._sums_fbo = self.ctx.framebuffer([self._sum, self._sum_sq])
        self._batch = self.ctx.texture(size, 4, dtype="f4")
        self._depth = self.ctx.depth_renderbuffer(size)
        colours = [self._batch]
        if shared:
            self._untraced = tuple(self.ctx.texture(size, 4, dtype="f4") for _ in range(3))
            colours.append(self._untraced[0])
        self._batch_fbo = self.ctx.framebuffer(colours, self._depth)
        self._depth_fbo = self.ctx.framebuffer(depth_attachment=self._depth)
        self._allocation = self.ctx.texture(size, 2, dtype="f4")
        self._allocation.filter = (moderngl.NEAREST, moderngl.NEAREST)

    def _release_preview(self) -> None:
        if self._preview_fbo is not None:
            for obj in (*self._preview_fbo.color_attachments, self._preview_fbo.depth_attachment):
                obj.release()
            self._preview_fbo.release()
        self._preview = self._preview_fbo = None

    def _release_targets(self) -> None:
        self._release_preview()
        targets = (self._depth_fbo, self._batch_fbo, self._sums_fbo, self._depth)
        for obj in (*targets, self._sum, self._sum_sq, self._batch, self._allocation):
            if obj is not None:
                obj.release()
        for tex in self._untraced or ():
            tex.release()
        self._untraced = None
        self._depth_fbo = self._batch_fbo = self._sums_fbo = self._depth = None
        self._sum = self._sum_sq = self._batch = self._allocation = None

    def release(self) -> None:
        """Free targets, sampling tables and tangent buffers; safe to call twice."""
        self._release_targets()
        self._tangent_buffers.release()
        if self._tables is not None:
            self._tables.release()
            self._tables = None
        if self._trace is not None:
            self._trace.release()
            self._trace = None
        self._key = self._trace_key = None


def estimate_shader_files() -> list[str]:
    """Files (relative to the shader root) of :data:`ESTIMATE_PROGRAMS` and all they include."""
    files: list[str] = []
    for program in ESTIMATE_PROGRAMS:
        _, source_map = preprocess(program, "COMPUTE_SHADER", read_shader)
        files += [name for name in source_map.files if name not in files]
    return sorted(files)


def _read_texture(tex: moderngl.Texture) -> npt.NDArray[np.float32]:
    """(h, w, 4) float32 of an RGBA32F target, row 0 at the top."""
    w, h = tex.size
    return np.frombuffer(tex.read(), dtype=np.float32).reshape(h, w, 4)[::-1].copy()


def _saved_snapshots(state: dict[str, npt.NDArray], batches: int) -> dict[int, npt.NDArray]:
    """Checkpoint estimates of a saved state, by batch count.

    States saved before session 5 hold one ``snapshot``: the estimate at the
    last doubling, the largest power of two up to ``batches``.
    """
    if "snapshots" in state:
        return {
            int(b): e.astype(np.float32)
            for b, e in zip(state["snapshot_batches"], state["snapshots"], strict=True)
        }
    if state["snapshot"].size:
        return {1 << (batches.bit_length() - 1): state["snapshot"].astype(np.float32)}
    return {}


def _batch_variance(
    total: npt.NDArray[np.float32], squares: npt.NDArray[np.float32]
) -> npt.NDArray[np.float32]:
    """(h, w, 3) sample variance of each pixel's batch means (inf with fewer than two)."""
    k = total[..., 3:]
    safe = np.maximum(k, 2.0)
    mean = total[..., :3] / safe
    variance = np.maximum(squares[..., :3] / safe - mean**2, 0.0) * safe / (safe - 1.0)
    return np.where(k >= 2, variance, np.float32(np.inf))


def median_relative_error(
    estimate: npt.NDArray[np.float32],
    error: npt.NDArray[np.float32],
    mask: npt.NDArray[np.bool_],
) -> float:
    """Median over ``mask`` of the luminance error over the luminance of the estimate.

    Parameters
    ----------
    estimate, error : (h, w, 3) float
        Mean radiance and its standard error per channel (channel errors
        are added in the luminance: an upper bound).
    mask : (h, w) bool
        The pixels measured; those of zero luminance are left out.

    Returns
    -------
    float
        Unitless; inf when no pixel of ``mask`` is lit.
    """
    estimate_y = estimate[mask] @ LUMINANCE
    error_y = error[mask] @ LUMINANCE
    lit = estimate_y > 0
    if not lit.any():
        return float("inf")
    return float(np.median(error_y[lit] / estimate_y[lit]))
