"""The reference's run for ``compare``: accumulated by Monte Carlo, evaluated exactly, or
traced with the exact untraced reference as its control variate.

:class:`ReferenceRun` is what the report reads of a reference. :func:`converge` accumulates
the ground truth until the judge's rule or its own budget stops it (with ``control``, judging
the control-variate estimate, :func:`control_variate`); :func:`exact_run` evaluates the
untraced ``phong`` model exactly at the methods' samples (measure/exact_reference.py);
:func:`untraced_run` takes the untraced estimate a traced run drew from the same samples.
"""

from __future__ import annotations

import contextlib
import sys
import time
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt
from tqdm import tqdm

from envstudio.core.env_sampling import LUMINANCE
from envstudio.core.images import displayed
from envstudio.engine.method import Method
from envstudio.engine.session import RenderSession
from envstudio.errors import ParameterError
from envstudio.measure import ground_truth_cache
from envstudio.measure.exact_cache import exact_path, load_frame, save_frame
from envstudio.measure.exact_lobes import LobeEvaluator
from envstudio.measure.exact_reference import CheckedError, exact_frame
from envstudio.measure.ground_truth import (
    SCENE_EFFECTS,
    UNTRACED_TOO,
    ConvergenceStatus,
    GroundTruth,
)
from envstudio.measure.stopping import (
    NOISE_RULE,
    NOISE_SHARE,
    TOLERANCE_RULE,
    ReferenceJudge,
    duration,
)
from envstudio.scene.tangents import TangentField

STOPPED_BY = {
    "reliable": "every method reliable",
    "converged": "converged",
    "max_samples": "sample budget spent",
    "time_limit": "time limit reached",
    "exact": "evaluated exactly (no sampling)",
}
"""What ends the reference's accumulation, as :attr:`ReferenceRun.stopped_by` names it."""
EXACT = "exact"
MONTE_CARLO = "montecarlo"
REFERENCE_KINDS = (EXACT, MONTE_CARLO)
"""``--reference``: the exact untraced reference where the model has one
(measure/exact_reference.py), or Monte Carlo throughout."""


#: A pixel's traced and untraced estimates differ when the spread of their difference is
#: above this share of the pixel's value (below it, float rounding of the two sums).
TRACED_SHARE = 1e-5


@dataclass
class ReferenceRun:
    """The converged (or budget-limited) reference.

    Attributes
    ----------
    parameters : dict
        Its parameter values.
    status : ConvergenceStatus
        Samples per pixel, last successive-half change, converged.
    frames_ms : list of float
        Wall time of each accumulation frame, ms.
    total_s : float
        Wall time from the first frame to the last, s.
    relative_standard_error : float
        Median over the mask of the luminance standard error over the luminance
        of the estimate (channel errors added: an upper bound).
    resumed_samples : int
        Samples per pixel taken over from a saved accumulation (0 when it
        started afresh; ``frames_ms`` and ``total_s`` count this run only).
    hdr : (h, w, 3) float32
        Linear radiance of the frame.
    display : (h, w, 3) float32
        The frame as displayed, in [0, 1].
    stopping_rule : str
        ``noise`` (the default) or ``tolerance`` (strict), measure/stopping.py.
    stopped_by : str
        A key of :data:`STOPPED_BY`: what ended the accumulation.
    wall_s : float
        Wall time of this run's accumulation, s (what ``time_limit`` counts:
        ``total_s`` plus the time between frames).
    exact_error : CheckedError or None
        For an exact run (measure/exact_reference.py), its checked relative error against
        the brute force, median and largest (``relative_standard_error`` holds the median:
        what the methods' reliability is judged by); for a control-variate run, that of its
        exact part (a method is reliable when both it and the noise are under a tenth of its
        error); None for a plain Monte Carlo run.
    control_variate : bool
        A traced run estimated as the exact untraced reference plus the sampled difference
        traced − untraced (:func:`control_variate`): ``hdr`` and the noise are that
        estimate's.
    pixel_noise : (h, w) float32 or None
        A control-variate run's relative standard error per pixel (0 where nothing is
        traced): what its methods' reliability is judged by
        (stopping.control_variate_uncertainty); None otherwise.
    half_hdr : (h, w, 3) float32 or None
        A control-variate run's estimate of at most half its samples (the drift of its
        methods' errors since then is judged too); None otherwise.
    """

    parameters: dict[str, object]
    status: ConvergenceStatus
    frames_ms: list[float]
    total_s: float
    relative_standard_error: float
    resumed_samples: int
    hdr: npt.NDArray[np.float32]
    display: npt.NDArray[np.float32]
    stopping_rule: str = TOLERANCE_RULE
    stopped_by: str = "converged"
    wall_s: float = 0.0
    exact_error: CheckedError | None = None
    control_variate: bool = False
    pixel_noise: npt.NDArray[np.float32] | None = None
    half_hdr: npt.NDArray[np.float32] | None = None

    @property
    def converged(self) -> bool:
        """The successive-half change fell below the tolerance within the budget."""
        return self.status.converged

    @property
    def unreliable_reason(self) -> str | None:
        """Why marked metrics cannot be trusted, or None when the reference converged."""
        if self.converged:
            return None
        if self.pixel_noise is not None and self.stopped_by == "reliable":
            return self._bound_text()  # the noise was judged enough: the bound was not
        if self.pixel_noise is not None:
            return (
                f"{self._stop_text()} and the control variate's noise where it traces (median "
                f"{100 * self.relative_standard_error:.3g} %) can move the marked methods' "
                f"median relative error by {NOISE_SHARE:g} of it or more ({self._advice()})"
            )
        if self.exact_error is not None:
            return self._bound_text()
        # batches of one Sobol sequence are negatively correlated: their spread overstates
        bound = (
            ", an upper bound under sequence=sobol"
            if self.parameters.get("sequence") == "sobol"
            else ""
        )
        return (
            f"{self._stop_text()} and its median relative standard error "
            f"({100 * self.relative_standard_error:.3g} %{bound}) is not below "
            f"{NOISE_SHARE:g} of the marked methods' median relative error, so its Monte Carlo "
            f"noise is part of their metrics ({self._advice()})"
        )

    def _bound_text(self) -> str:
        """The exact reference's checked error is what marks the methods."""
        checked = self.exact_error
        return (
            f"the exact reference's checked error (median {100 * checked.median:.3g} %, "
            f"largest {100 * checked.largest:.3g} % against the brute force) is not below "
            f"{NOISE_SHARE:g} of the marked methods' median relative error"
        )

    def _stop_text(self) -> str:
        """How the reference stopped short, with the half-change under the tolerance rule."""
        if self.stopped_by == "time_limit":
            text = (
                f"the reference reached its time limit of {float(self.parameters['time_limit']):g}"
                " s before it converged"
            )
        else:
            text = (
                f"the reference did not converge within max_samples="
                f"{self.parameters['max_samples']} spp"
            )
        if self.stopping_rule != TOLERANCE_RULE:
            return text
        change = self.status.rms_change
        measured = (
            "no convergence check yet (fewer than 2 frames)"
            if change is None
            else f"half-change {100 * change:.3g} % > tolerance "
            f"{100 * float(self.parameters['tolerance']):.3g} %"
        )
        return f"{text} ({measured})"

    def _advice(self) -> str:
        """What to raise to get reliable numbers."""
        raised = "--time-limit" if self.stopped_by == "time_limit" else "max_samples"
        return (
            f"raise {raised} or tolerance"
            if self.stopping_rule == TOLERANCE_RULE
            else (f"raise {raised}")
        )


def converge(
    session: RenderSession,
    reference: GroundTruth,
    size: tuple[int, int],
    progress: bool,
    cache: bool,
    judge: ReferenceJudge,
    control: tuple[npt.NDArray[np.float32], npt.NDArray[np.bool_]] | None = None,
) -> tuple[ReferenceRun, npt.NDArray[np.bool_]]:
    """Accumulate until ``judge``'s rule or the reference stops it; the run and the mask.

    Resumed and saved with ``cache``. With ``control`` (the exact untraced frame and its
    mask, the reference accumulating ``untraced_too``) the image judged and returned is the
    control variate's (:func:`control_variate`). Raises on an empty mask.
    """
    frames_ms: list[float] = []
    checkpoint = ground_truth_cache.Checkpoint(session, reference, size) if cache else None
    with (
        tqdm(
            desc=reference.name,
            unit="frame",
            file=sys.stderr,
            disable=not progress,
            bar_format="{desc}: {elapsed}{postfix}",
        ) as bar,
        checkpoint.saved_on_interrupt() if checkpoint else contextlib.nullcontext(),
    ):
        frames_ms.append(timed_frame(session, reference, size))
        mask = reflector_mask(session, reference)
        kept = KeptEstimates()
        while True:
            if judge.due(reference.status.batches):
                if control is None:
                    judge.judge(reference, session.read_hdr(), mask)
                else:
                    hdr, _, noise, pixel_noise = control_variate(session, reference, control, mask)
                    batches = reference.status.batches
                    half = kept.half(batches)
                    kept.keep(batches, hdr)
                    judge.judge(reference, hdr, mask, noise, pixel_noise, half)
            if progress:
                bar.set_postfix_str(progress_line(reference, judge), refresh=False)
                bar.update()
            if reference.finished() or judge.satisfied():
                break
            frames_ms.append(timed_frame(session, reference, size))
            if checkpoint:
                checkpoint.save_if_due()
    wall_s = reference.status.run_elapsed()
    resumed = 0
    if checkpoint:
        checkpoint.save()
        resumed = checkpoint.resumed_samples
    if resumed:
        print(f"reference: resumed at {resumed} spp from {checkpoint.path}", file=sys.stderr)
    stopped_by = "reliable" if judge.satisfied() else reference.stop_reason()
    pixel_noise = half = None
    if control is None:
        hdr, noise = session.read_hdr(), reference.relative_standard_error()
    else:
        hdr, _, noise, pixel_noise = control_variate(session, reference, control, mask)
        half = kept.half(reference.status.batches)
    print(f"reference: {stop_line(reference, noise, wall_s, stopped_by)}", file=sys.stderr)
    run = ReferenceRun(
        parameters=reference.values.as_dict(),
        status=replace(reference.status),
        frames_ms=frames_ms,
        total_s=sum(frames_ms) / 1e3,
        relative_standard_error=noise,
        resumed_samples=resumed,
        hdr=hdr,
        display=display_image(session, hdr),
        stopping_rule=judge.rule,
        stopped_by=stopped_by,
        wall_s=wall_s,
        control_variate=control is not None,
        pixel_noise=pixel_noise,
        half_hdr=half,
    )
    return run, mask


class KeptEstimates:
    """A control variate's estimates at the batch counts it was judged at, for the estimate
    of half the samples (stopping.control_variate_uncertainty); the accumulation is
    cumulative, so the estimate at b batches is that of the first b batches' samples."""

    def __init__(self) -> None:
        self._by_batches: dict[int, npt.NDArray[np.float32]] = {}

    def keep(self, batches: int, hdr: npt.NDArray[np.float32]) -> None:
        self._by_batches[batches] = hdr

    def half(self, batches: int) -> npt.NDArray[np.float32] | None:
        """The latest estimate of at most half of ``batches`` (None: none yet); earlier ones,
        which no later count asks for, are dropped."""
        earlier = [b for b in self._by_batches if b <= batches // 2]
        if not earlier:
            return None
        latest = max(earlier)
        for b in earlier:
            if b < latest:
                del self._by_batches[b]
        return self._by_batches[latest]


def control_variate(
    session: RenderSession,
    reference: GroundTruth,
    control: tuple[npt.NDArray[np.float32], npt.NDArray[np.bool_]],
    mask: npt.NDArray[np.bool_],
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.bool_], float, npt.NDArray[np.float32]]:
    """The traced reference with the untraced estimate of the same samples as its control
    variate (ground_truth.PairedEstimates.controlled): T − β (U − exact untraced).

    Both Monte Carlo estimates come from the same samples, so where the scene adds little
    (occlusion, local and self-reflections) T and U vary together and only what it adds is
    left to sample: nothing where nothing is traced. Unbiased up to the exact reference's
    stated error and the footprint (the exact one's samples are the methods' grid, the
    sampled ones random points of the footprint); β per pixel, so never noisier than T.

    Returns
    -------
    hdr : (h, w, 3) float32
        The control-variate estimate on the pixels the exact run covers, the plain traced
        estimate elsewhere (a silhouette pixel only the traced footprint reaches).
    mask : (h, w) bool
        ``mask``, as judged.
    noise : float
        Median of the estimate's luminance standard error over its luminance (channel errors
        added: an upper bound, as the reference's) over the pixels of ``mask`` where the
        traced and untraced estimates differ (where something is traced); 0 where none do.
    pixel_noise : (h, w) float32
        That ratio at every pixel: 0 where nothing is traced, inf where traced and black
        or where the exact run does not cover the pixel (stopping.control_variate_uncertainty
        judges the methods by it).
    """
    exact, covered = control[0], control[1][..., None]
    paired = reference.paired()
    estimate, error = paired.controlled(exact)
    hdr = np.where(covered, estimate, session.read_hdr()).astype(np.float32)
    # the noise where sampling is left: the pixels whose traced and untraced estimates differ
    # by more than float rounding (elsewhere the estimate is the exact value, and a median
    # over them would hide the rest)
    spread_y = np.nan_to_num(paired.difference_error, posinf=np.inf) @ LUMINANCE
    traced = mask & (spread_y > TRACED_SHARE * np.abs(hdr @ LUMINANCE))
    luminance = hdr @ LUMINANCE
    spread = np.where(covered, error, np.inf) @ LUMINANCE
    with np.errstate(divide="ignore", invalid="ignore"):
        relative = np.where(luminance > 0, spread / luminance, np.inf)
    # a pixel only the traced footprint reaches holds a plain traced estimate: unknown
    pixel_noise = np.where(traced | ~control[1], relative, 0.0).astype(np.float32)
    if not traced.any():
        return hdr, mask, 0.0, pixel_noise
    lit = traced & (luminance > 0)
    noise = float(np.median(relative[lit])) if lit.any() else float("inf")
    return hdr, mask, noise, pixel_noise


def exact_run(
    session: RenderSession,
    reference: GroundTruth,
    size: tuple[int, int],
    ssaa: int,
    background: npt.NDArray[np.float32] | None,
    cache: bool = False,
    lobes: LobeEvaluator | None = None,
) -> tuple[ReferenceRun, npt.NDArray[np.bool_]]:
    """The untraced model evaluated exactly at ``ssaa``² samples a pixel (exact_reference.py),
    as a run, and its mask; off the reflectors ``background`` (a method's frame) or black.
    With ``cache``, a frame of the same inputs evaluated before is read back
    (measure/exact_cache.py) and a new one kept. ``lobes``: the caller's GPU evaluation of
    the glossy lobes (its pyramid kept between runs), else one made and freed here.

    Raises
    ------
    ParameterError
        If the camera sees no reflector (empty mask).
    """
    started = time.perf_counter()
    fine = (size[0] * ssaa, size[1] * ssaa)
    normals, views = session.renderer.reflector_surface(session.gpu_scene, session.camera, fine)
    values = reference.values.as_dict()
    tangents = None
    if values["model"] == "banks":
        field = TangentField(str(values["tangent_field"]), str(values["tangent_axis"]))
        tangents = session.renderer.reflector_tangents(
            session.gpu_scene, session.camera, fine, field
        )
    radiance = session.scene.environment.radiance
    path = exact_path(radiance, normals, views, tangents, values, ssaa) if cache else None
    frame = load_frame(path) if path is not None else None
    saved = frame is not None
    if not saved:
        own = LobeEvaluator(session.ctx, session.programs) if lobes is None else None
        try:
            frame = exact_frame(
                normals, views, radiance, values, ssaa, started, lobes or own, tangents
            )
        finally:
            if own is not None:
                own.release()
        if path is not None:
            save_frame(path, frame)
    if not frame.mask.any():
        empty_mask(session)
    outside = np.zeros_like(frame.hdr) if background is None else background
    hdr = np.where(frame.mask[..., None], frame.hdr, outside).astype(np.float32)
    checked = frame.error
    how = f"in {frame.seconds:.2f} s"
    how = f"read back (evaluated {how})" if saved else how
    print(
        f"reference: exact {how}; against the brute force at "
        f"{checked.describe()}: median {100 * checked.median:.2g} %, largest "
        f"{100 * checked.largest:.2g} %",
        file=sys.stderr,
    )
    run = ReferenceRun(
        parameters=reference.values.as_dict(),
        status=ConvergenceStatus(),
        frames_ms=[1e3 * frame.seconds],
        total_s=frame.seconds,
        relative_standard_error=checked.median,
        resumed_samples=0,
        hdr=hdr,
        display=display_image(session, hdr),
        stopping_rule=EXACT,
        stopped_by=EXACT,
        wall_s=time.perf_counter() - started,
        exact_error=frame.error,
    )
    return run, frame.mask


def untraced_run(
    session: RenderSession, reference: GroundTruth, traced: ReferenceRun, mask
) -> ReferenceRun:
    """The untraced estimate the traced run accumulated from the same samples, as a run."""
    hdr = np.where(mask[..., None], reference.untraced_estimate(), traced.hdr).astype(np.float32)
    return replace(
        traced,
        parameters=traced.parameters | {SCENE_EFFECTS: False, UNTRACED_TOO: False},
        relative_standard_error=reference.untraced_relative_standard_error(),
        hdr=hdr,
        display=display_image(session, hdr),
    )


def reflector_mask(session: RenderSession, reference: GroundTruth) -> npt.NDArray[np.bool_]:
    """The reference's coverage after its first frame.

    Raises
    ------
    ParameterError
        If it is empty: the camera sees no reflector.
    """
    mask = reference.coverage()
    if not mask.any():
        empty_mask(session)
    return mask


def empty_mask(session: RenderSession) -> None:
    """Raise the one line for a camera that sees no reflector."""
    camera = session.camera
    raise ParameterError(
        f"camera at azimuth {camera.azimuth:g}°, elevation {camera.elevation:g}°, "
        f"distance {camera.distance:g} sees no reflector (empty mask): nothing to compare"
    )


def stop_line(reference: GroundTruth, noise: float, wall_s: float, stopped_by: str) -> str:
    """Where the reference stopped: samples, time, noise, half-change, and why."""
    status = reference.status
    change = "—" if status.rms_change is None else f"{100 * status.rms_change:.3g} %"
    state = "converged" if status.converged else "NOT converged"
    noise_text = f"{100 * noise:.3g} %" if np.isfinite(noise) else "—"
    return (
        f"{status.samples} spp in {wall_s:.1f} s, noise {noise_text}, half-change {change} "
        f"({state}); stopped: {STOPPED_BY[stopped_by]}"
    )


def progress_line(reference: GroundTruth, judge: ReferenceJudge) -> str:
    """The reference's status and, once judged, the noise, every method's error and time left."""
    line = judge.progress_line()
    if judge.rule != NOISE_RULE or not line:
        return f"{reference.status_line()}; {line}" if line else reference.status_line()
    limit = float(reference.values["time_limit"])
    if limit > 0:
        line += f"; time limit in {duration(limit - reference.status.run_elapsed())}"
    return f"{reference.status.samples} spp, {line}"


def timed_frame(session: RenderSession, method: Method, size: tuple[int, int]) -> float:
    """Render one frame; its wall time in ms with ``finish()`` at both ends (as bench)."""
    session.ctx.finish()
    start = time.perf_counter()
    session.render_offscreen(method, size)
    session.ctx.finish()
    return (time.perf_counter() - start) * 1e3


def display_image(session: RenderSession, hdr: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
    """(h, w, 3) float32 display values of linear ``hdr`` with the session's display settings
    (core/images.py's twin of the display shader), unquantised, in [0, 1]."""
    display = session.renderer.display
    return displayed(hdr, float(display["exposure"]), str(display["tonemap"])).astype(np.float32)
