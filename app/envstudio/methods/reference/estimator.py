"""The estimator: shaders/reference/accumulate.glsl set up for a frame, and how its draws add up.

Samples come from one Owen-scrambled Sobol sequence per pixel continued
across batches (``sequence=sobol``) or from independent batches
(``sequence=random``); each pixel draws its allocation's share of a batch, in
chunks of at most :meth:`Estimator.chunk_samples` per draw call. Estimates add
up with additive blending on the nearest surface (:func:`adding`).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import moderngl
import numpy as np

from envstudio.gpu.context import is_software_renderer, require_version
from envstudio.gpu.programs import ProgramLibrary
from envstudio.methods.reference.accumulation import Accumulation
from envstudio.methods.reference.environment_tables import EnvironmentTables
from envstudio.methods.reference.parameters import MODELS, SEQUENCES
from envstudio.methods.reference.sample_allocation import (
    MAX_MULTIPLIER,
    SOFTWARE_SAMPLES_PER_BATCH,
)
from envstudio.methods.reference.tracing import TraceData
from envstudio.plugin import FrameInputs, GpuScene, ParameterValues, set_uniform


class Estimator:
    """The reference's estimator program, set up for a frame.

    Owns what the shader reads besides the scene's own buffers: the
    environment's sampling tables (remade when the environment changes) and
    the scene's triangles for tracing (when the geometry changes).

    Parameters
    ----------
    ctx : moderngl.Context
        Where it draws.
    programs : ProgramLibrary
        The method's shader programs.
    values : ParameterValues
        The method's parameters, read at every draw.
    """

    def __init__(self, ctx: moderngl.Context, programs: ProgramLibrary, values: ParameterValues):
        self.ctx = ctx
        self.programs = programs
        self.values = values
        self._tables: EnvironmentTables | None = None
        self._tables_revision = -1
        self._trace: TraceData | None = None
        self._trace_key: tuple | None = None

    def prepare(self, scene: GpuScene) -> None:
        """Remake the sampling tables and the traced triangles where the scene changed."""
        if self._tables_revision != scene.environment_revision:
            if self._tables is not None:
                self._tables.release()
            self._tables = EnvironmentTables(self.ctx, scene.scene.environment.radiance)
            self._tables_revision = scene.environment_revision
        geometry = (id(scene), scene.geometry_revision)
        if self.uses_bvh() and geometry != self._trace_key:
            if self._trace is not None:
                self._trace.release()
            self._trace = TraceData(self.ctx, scene)
            self._trace_key = geometry

    def shares_untraced(self) -> bool:
        """Whether each batch also gives the untraced estimate (``untraced_too`` with tracing)."""
        return bool(self.values["trace"] and self.values["untraced_too"])

    def uses_bvh(self) -> bool:
        """Whether the scene's triangles are traced: for local light or for the pixel footprint."""
        return bool(self.values["trace"] or self.values["pixel_filter"])

    def program(
        self,
        frame: FrameInputs,
        size: tuple[int, int],
        samples: int,
        batches: int,
        accumulation: Accumulation,
    ) -> moderngl.Program:
        """The estimator with this frame's uniforms, for a target of ``size`` (w, h) pixels at
        ``samples`` per pixel and batch, after ``batches`` batches of ``accumulation``."""
        trace = bool(self.values["trace"])
        require_version(self.ctx, 430, "method reference needs OpenGL 4.3 (storage buffers)")
        defines = {"TRACE_LOCAL": int(trace), "UNTRACED_TOO": int(self.shares_untraced())}
        if self.uses_bvh():
            defines["TRACE_STACK"] = self._trace.stack_size
        program = self.programs.get("reference/accumulate.glsl", defines)
        scene = frame.scene
        scene.latlong.use(location=0)
        set_uniform(program, "u_latlong", 0)
        self._tables.bind(program, 1)
        if self.uses_bvh():
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
        set_uniform(program, "u_frame", batches)
        set_uniform(program, "u_adaptive", bool(self.values["adaptive"]))
        set_uniform(program, "u_batches_since_allocation", batches - accumulation.allocation.at)
        accumulation.allocation_texture.use(location=4)
        set_uniform(program, "u_allocation", 4)
        return program

    def chunk_samples(self) -> int:
        """Estimates a pixel draws per draw call: ``samples_per_draw``, else the whole batch.

        llvmpipe silently ends an invocation's loops after 65 535 iterations in
        all (:data:`SOFTWARE_SAMPLES_PER_BATCH`), so there a chunk is at most
        that many samples. The batch target adds the chunks up.
        """
        chunk = int(self.values["samples_per_draw"]) or int(self.values["samples"]) * MAX_MULTIPLIER
        if is_software_renderer(self.ctx):
            return min(chunk, SOFTWARE_SAMPLES_PER_BATCH)
        return chunk

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

    def release(self) -> None:
        """Free the sampling tables and traced triangles; safe to call twice."""
        if self._tables is not None:
            self._tables.release()
            self._tables = None
        if self._trace is not None:
            self._trace.release()
            self._trace = None
        self._trace_key = None


@contextlib.contextmanager
def adding(ctx: moderngl.Context) -> Iterator[None]:
    """Additive blending onto the nearest surface (depth ``<=``): how estimates accumulate.

    With additive blending every fragment passing a plain depth test would
    count, so the estimates test ``<=`` against the depth prepass's depth.
    """
    ctx.enable(moderngl.DEPTH_TEST | moderngl.BLEND)
    ctx.depth_func = "<="
    ctx.blend_func = moderngl.ONE, moderngl.ONE
    ctx.blend_equation = moderngl.FUNC_ADD
    try:
        yield
    finally:
        ctx.disable(moderngl.BLEND)
        ctx.blend_func = moderngl.DEFAULT_BLENDING
        ctx.depth_func = "<"
