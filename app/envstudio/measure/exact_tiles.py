"""The viewer's grid tiles measured against the exact reference of the view (issue 40 item 5).

For a tile of a reflectance model with an exact untraced evaluation
(exact_reference.EXACT_MODELS), the reference is that model at the tile's f_λ, k_d and
Phong exponent (the caller derives them as ``compare`` matches glossiness), evaluated exactly
at ``ssaa`` × ``ssaa`` footprint samples a pixel of the tile's render size: what ``compare
--reference exact --param trace=false --ssaa S`` takes as its reference at that size.
:class:`ExactTiles` does the work in steps, each a fraction of a second, so a window keeps
drawing between them:

1. the reflectors' surface at the samples (engine FrameRenderer.reflector_surface), once per
   size and reference;
2. the exact radiance (exact_reference.exact_radiance) in chunks of :data:`CHUNK` samples
   (:data:`LOBE_CHUNK` for a lobe the GPU integrates),
   averaged over each pixel's covered samples once all are done;
3. one tile a step: its method rendered at the same samples, box-filtered as compare filters
   it (compare.footprint_filter), and measured as compare measures it: the median relative
   luminance error over the reflector (stopping.median_error) and PSNR of the display images
   over it (core.metrics.psnr).

Tiles with the same reference values and size share one frame. Unlike compare, the
reference's brute-force check (exact_reference.checked_error, seconds at a large map) is not
run: it does not change the frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.images import displayed
from envstudio.core.metrics import psnr
from envstudio.engine.frame import FrameRenderer
from envstudio.engine.method import Method, Session
from envstudio.gpu.programs import ProgramLibrary
from envstudio.measure.cached_reference import render_finished
from envstudio.measure.compare import footprint_filter
from envstudio.measure.exact_lobes import LobeEvaluator
from envstudio.measure.exact_reference import LOBE_MODELS, exact_radiance
from envstudio.measure.stopping import median_error
from envstudio.scene.tangents import TangentField

SSAA = 2
"""Footprint samples per pixel per axis of the tiles' reference and their methods."""
CHUNK = 1 << 16
#: Samples shaded a step for a model whose lobe the GPU integrates (exact_lobes.py): about a
#: second on llvmpipe.
LOBE_CHUNK = 1 << 12
"""Samples shaded per step."""


@dataclass(frozen=True)
class TileRequest:
    """A tile to measure.

    Attributes
    ----------
    method : Method
        The tile's method, as it renders in the grid.
    values : dict
        The reference's ``fresnel``, ``kd`` and ``phong_exponent`` at that tile.
    size : (int, int)
        The tile's render size, pixels.
    """

    method: Method
    values: dict[str, object]
    size: tuple[int, int]


@dataclass(frozen=True)
class ExactNumbers:
    """A tile against its exact reference: compare's median relative error and PSNR (dB)."""

    median_relative_error: float
    psnr_db: float


@dataclass
class _Frame:
    """One exact reference frame as it is built: its samples, then its pixels."""

    values: dict[str, object]
    size: tuple[int, int]
    normals: npt.NDArray[np.float32] | None = None
    views: npt.NDArray[np.float32] | None = None
    covered: npt.NDArray[np.bool_] | None = None
    tangents: npt.NDArray[np.float32] | None = None
    shaded: list[npt.NDArray[np.float32]] = field(default_factory=list)
    hdr: npt.NDArray[np.float32] | None = None
    mask: npt.NDArray[np.bool_] | None = None


class ExactTiles:
    """Tiles measured one step at a time against the exact reference of their view.

    Parameters
    ----------
    ctx, programs
        The context and its program cache (a renderer of its own draws the samples).
    ssaa
        Footprint samples per pixel per axis.
    """

    def __init__(self, ctx: moderngl.Context, programs: ProgramLibrary, ssaa: int = SSAA):
        self.ssaa = ssaa
        self._ctx, self._programs = ctx, programs
        self._renderer: FrameRenderer | None = None
        self._lobes = LobeEvaluator(ctx, programs)
        self._frames: dict[str, _Frame] = {}
        self._queue: list[tuple[str, Method, _Frame]] = []

    @property
    def pending(self) -> bool:
        """Whether a tile is still to be measured."""
        return bool(self._queue)

    def start(self, requests: dict[str, TileRequest]) -> None:
        """Measure these tiles (tile name → request) from now on, forgetting any before."""
        self.clear()
        for name, request in requests.items():
            key = repr((request.size, sorted(request.values.items())))
            frame = self._frames.setdefault(key, _Frame(dict(request.values), request.size))
            self._queue.append((name, request.method, frame))

    def clear(self) -> None:
        """Drop the tiles and the frames (the view changed)."""
        self._frames, self._queue = {}, []

    def step(
        self, session: Session, display: dict[str, object]
    ) -> tuple[str, ExactNumbers | None] | None:
        """One piece of work for the next tile: None while its reference is being built, then
        its name and numbers (None: no reflector in view, or its input is missing).

        Parameters
        ----------
        session
            The GPU scene, camera and environment (the view the tiles were started for).
        display
            Exposure and tone map of the display images PSNR is taken on.
        """
        name, method, frame = self._queue[0]
        if frame.mask is None:
            self._build(session, frame)
            return None
        self._queue.pop(0)
        if not frame.mask.any():
            return name, None
        hdr = self._render(session, method, frame.size)
        if method.missing_input():
            return name, None
        exposure, tonemap = float(display["exposure"]), str(display["tonemap"])
        shown = displayed(hdr, exposure, tonemap).astype(np.float32)
        truth = displayed(frame.hdr, exposure, tonemap).astype(np.float32)
        numbers = ExactNumbers(
            median_error(hdr, frame.hdr, frame.mask), psnr(shown, truth, frame.mask)
        )
        return name, numbers

    def _build(self, session: Session, frame: _Frame) -> None:
        """The surface pass, one chunk of shading, or the pixels: whichever comes next."""
        fine = (frame.size[0] * self.ssaa, frame.size[1] * self.ssaa)
        if frame.normals is None:
            renderer = self._frame_renderer()
            frame.normals, frame.views = renderer.reflector_surface(
                session.gpu_scene, session.camera, fine
            )
            frame.covered = np.linalg.norm(frame.normals, axis=-1) > 0.5
            values = frame.values
            if values["model"] == "banks":
                field = TangentField(str(values["tangent_field"]), str(values["tangent_axis"]))
                tangents = renderer.reflector_tangents(
                    session.gpu_scene, session.camera, fine, field
                )
                frame.tangents = tangents[frame.covered]
            return
        normals, views = frame.normals[frame.covered], frame.views[frame.covered]
        done = sum(len(chunk) for chunk in frame.shaded)
        if done < len(normals):
            size = LOBE_CHUNK if frame.values.get("model") in LOBE_MODELS else CHUNK
            chunk = slice(done, done + size)
            radiance = session.scene.environment.radiance
            tangents = None if frame.tangents is None else frame.tangents[chunk]
            frame.shaded.append(
                exact_radiance(
                    radiance, normals[chunk], views[chunk], frame.values, self._lobes, tangents
                )
            )
            return
        samples = np.zeros(frame.normals.shape, dtype=np.float32)
        if frame.shaded:
            samples[frame.covered] = np.concatenate(frame.shaded)
        frame.hdr = footprint_filter(samples, frame.covered, self.ssaa)
        w, h = frame.size
        frame.mask = frame.covered.reshape(h, self.ssaa, w, self.ssaa).any(axis=(1, 3))

    def _render(
        self, session: Session, method: Method, size: tuple[int, int]
    ) -> npt.NDArray[np.float32]:
        """``method``'s frame at ``size`` × ssaa, until it is finished, box-filtered."""
        fine = (size[0] * self.ssaa, size[1] * self.ssaa)
        renderer = self._frame_renderer()
        hdr = render_finished(renderer, session, method, fine)
        covered = renderer.reflector_coverage(session.gpu_scene, session.camera, fine)
        return footprint_filter(hdr, covered, self.ssaa)

    def _frame_renderer(self) -> FrameRenderer:
        if self._renderer is None:
            self._renderer = FrameRenderer(self._ctx, self._programs)
        return self._renderer

    def release(self) -> None:
        """Free the renderer's GPU objects; safe twice."""
        if self._renderer is not None:
            self._renderer.release()
        self._renderer = None
        self._lobes.release()
        self.clear()
