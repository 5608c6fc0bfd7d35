"""When ``envstudio compare`` stops accumulating the reference.

Two rules:

``noise`` (the default)
    A method's numbers count as reliable when the reference's own noise (its
    median relative standard error over the reflector,
    :meth:`GroundTruth.relative_standard_error`) is under
    :data:`NOISE_SHARE` of that method's median relative error against the
    reference; the reference stops as soon as this holds for every compared
    method (at two judgements in a row for a method within :data:`MARGIN` of
    its limit). The methods are rendered first (one frame each) and their errors
    are judged against the current estimate at the reference's checkpoints
    (:func:`~envstudio.measure.ground_truth.is_checkpoint`) and every
    :data:`JUDGE_INTERVAL_S` seconds, never before :data:`MIN_JUDGED_BATCHES`
    batches (with fewer, the spread of the batch means underestimates the
    noise).
``tolerance`` (strict)
    The reference's own successive-half criterion: it stops when the change
    falls below ``tolerance``. Used with ``--strict``, when ``tolerance`` is
    given explicitly, and when only the reference itself is compared.

With a control-variate reference (measure/reference_runs.control_variate) the noise is
zero wherever nothing is traced, so one median over the reflector would hide the pixels
still sampled and one over those alone would ask more than the metric needs: each method's
uncertainty is then :func:`control_variate_uncertainty`: twice the standard error of the
median with its drift since half the samples (a bias the noise does not show), and the rule
holds when that is under :data:`NOISE_SHARE` of its error. On a
convex reflector without local objects it is zero at once: nothing is left to sample.

Under either rule the reference also stops on its sample budget
(``max_samples``) or its time limit (``time_limit``). Noise falls as
1/sqrt(samples), so the samples still needed are projected from the current
noise and the smallest error, and the time from this run's samples per second.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from envstudio.core.env_sampling import LUMINANCE
from envstudio.core.metrics import RELATIVE_FLOOR, relative_error
from envstudio.engine.registry import ground_truth_class
from envstudio.measure.ground_truth import GroundTruth, duration, is_checkpoint

NOISE_SHARE = 0.1
"""Largest ratio of reference noise to a method's error for its metrics to count as reliable."""
NOISE_RULE = "noise"
TOLERANCE_RULE = "tolerance"
JUDGE_INTERVAL_S = 5.0
"""Longest wait between two judgements, s (checkpoints grow far apart late in a run)."""
MIN_JUDGED_BATCHES = 8
"""Batches before the noise rule may stop: the median of the per-pixel spread of k batch
means is biased low by a factor sqrt(median(chi²_{k-1}) / (k - 1)), 0.95 at k = 8."""
UNCERTAINTY_DRAWS = 128
"""Bootstrap copies of a control-variate reference in :func:`median_error_uncertainty` (the
standard error it returns is itself known to about 1 / sqrt(2 × 128), 6 %)."""
UNCERTAINTY_SEED = 40
CONFIDENCE = 2.0
"""Standard errors a control variate's uncertainty is counted at (about 95 % where it is
normal): the bootstrap and the drift are estimates themselves, judged many times a run."""
MARGIN = 0.5
"""A method whose uncertainty is under this share of its limit (:data:`NOISE_SHARE` of its
error) passes at once; one between it and the limit passes only at two judgements in a row.
The uncertainty is itself an estimate, judged many times a run: stopping at its first dip
under the limit passed hwconv's scene error 16 % off on the bunny at k_d = 0.3
(studies/exact-reference/README.md, "Next-event estimation")."""
DRAWS_AT_ONCE = 16
"""Copies held in memory together (16 × 256² pixels × 8 bytes: 8 MiB an array)."""


@dataclass(frozen=True)
class Judgement:
    """The reference's noise and each method's error against it, at one moment.

    Attributes
    ----------
    batches, samples : int
        The reference's batches and samples per pixel.
    seconds : float
        Wall seconds of this run's accumulation (:meth:`ConvergenceStatus.run_elapsed`).
    noise : float
        Median relative standard error of the reference over the reflector.
    errors : dict
        Method name → median relative luminance error against the reference.
    uncertainties : dict or None
        Method name → :func:`control_variate_uncertainty` of its error, where the reference's
        noise is known per pixel (a control variate's); None: ``noise`` stands for every
        method.
    """

    batches: int
    samples: int
    seconds: float
    noise: float
    errors: dict[str, float]
    uncertainties: dict[str, float] | None = None

    def uncertainty(self, name: str) -> float:
        """How much of method ``name``'s error may be the reference's noise."""
        return self.noise if self.uncertainties is None else self.uncertainties[name]

    def reliable(self, name: str) -> bool:
        """Whether method ``name``'s numbers can be trusted by the noise rule."""
        return self.uncertainty(name) < NOISE_SHARE * self.errors[name]

    @property
    def shortfall(self) -> float:
        """The largest ratio of a method's uncertainty to :data:`NOISE_SHARE` of its error
        (below 1: every method reliable)."""
        return (
            max(
                (self.uncertainty(n) / (NOISE_SHARE * e) if e > 0 else math.inf)
                for n, e in self.errors.items()
            )
            if self.errors
            else 0.0
        )

    @property
    def all_reliable(self) -> bool:
        """Every method's numbers can be trusted."""
        return all(self.reliable(name) for name in self.errors)

    @property
    def target(self) -> float:
        """The noise to reach: :data:`NOISE_SHARE` of the smallest error."""
        return NOISE_SHARE * min(self.errors.values(), default=math.inf)


def choose_rule(names: list[str], reference_values: dict[str, object], strict: bool) -> str:
    """The stopping rule of a comparison of ``names``.

    Parameters
    ----------
    names
        The methods compared.
    reference_values
        The reference's ``--param`` values (a ``tolerance`` among them asks for the strict rule).
    strict
        ``--strict``.

    Returns
    -------
    str
        :data:`TOLERANCE_RULE` when strict, when ``tolerance`` is given, or when no method but
        the reference is compared (nothing to judge the noise against); else :data:`NOISE_RULE`.
    """
    truth = ground_truth_class().name
    others = [name for name in names if name != truth]
    if strict or "tolerance" in reference_values or not others:
        return TOLERANCE_RULE
    return NOISE_RULE


def median_error(
    hdr: npt.NDArray[np.float32], reference_hdr: npt.NDArray[np.float32], mask: npt.NDArray
) -> float:
    """Median over ``mask`` of the relative luminance error (core/metrics.py) of ``hdr``."""
    return float(np.median(relative_error(hdr, reference_hdr)[mask]))


def median_error_uncertainty(
    hdr: npt.NDArray[np.float32],
    reference_hdr: npt.NDArray[np.float32],
    pixel_noise: npt.NDArray,
    mask: npt.NDArray,
    draws: int = UNCERTAINTY_DRAWS,
) -> float:
    """The standard error of :func:`median_error` that the reference's per-pixel noise causes.

    A parametric bootstrap: each of ``draws`` copies of the reference moves every pixel's
    luminance by its own noise, Y (1 + σ z) with z standard normal, independently per pixel
    (the reference draws each pixel's samples from its own scrambled sequence,
    shaders/common/sobol.glsl); the result is the root mean square of the copies' median
    errors about the observed one. A pixel of unknown noise (σ = inf) takes an error of 0 or
    inf at even odds. The draws are seeded: the same images give the same number.

    Independent pixels move a median far less than the same σ moving every pixel one way: on
    the knot a median error of 8 % has a standard error of about 0.1 % where most pixels
    trace with a median noise of 5 % (studies/exact-reference/README.md, "The median's
    standard error").

    Parameters
    ----------
    hdr, reference_hdr : (h, w, 3) float32
        The method's frame and the reference, linear.
    pixel_noise : (h, w) float
        The reference's relative standard error per pixel (0 where it is exact, inf where
        unknown).
    mask : (h, w) bool
        The pixels compared.
    draws : int
        Bootstrap copies.

    Returns
    -------
    float
        Unitless, ≥ 0.
    """
    sigma = np.asarray(pixel_noise, dtype=np.float64)[mask]
    noisy = sigma > 0
    if not noisy.any():
        return 0.0
    error = relative_error(hdr, reference_hdr)[mask].astype(np.float64)
    observed, exact = np.median(error), error[~noisy]
    y_method = (np.asarray(hdr, dtype=np.float64) @ LUMINANCE)[mask]
    y_reference = (np.asarray(reference_hdr, dtype=np.float64) @ LUMINANCE)[mask]
    rng = np.random.default_rng(UNCERTAINTY_SEED)
    known = np.isfinite(sigma[noisy])
    medians = []
    for first in range(0, draws, DRAWS_AT_ONCE):
        z = rng.standard_normal((min(DRAWS_AT_ONCE, draws - first), int(noisy.sum())))
        moved = y_reference[noisy] * np.maximum(1.0 + np.where(known, sigma[noisy], 0.0) * z, 0.0)
        errors = np.abs(y_method[noisy] - moved) / np.maximum(moved, RELATIVE_FLOOR)
        errors = np.where(known, errors, np.where(z > 0.0, np.inf, 0.0))
        everything = np.concatenate([errors, np.broadcast_to(exact, (len(z), exact.size))], axis=1)
        medians.append(np.median(everything, axis=1))
    medians = np.concatenate(medians)
    return float(np.sqrt(np.mean((medians - observed) ** 2)))


def control_variate_uncertainty(
    hdr: npt.NDArray[np.float32],
    reference_hdr: npt.NDArray[np.float32],
    pixel_noise: npt.NDArray,
    mask: npt.NDArray,
    half_hdr: npt.NDArray[np.float32] | None,
) -> float:
    """What a control-variate reference leaves uncertain in a method's median error:
    :data:`CONFIDENCE` times the standard error its noise gives the median
    (:func:`median_error_uncertainty`) and its drift since the estimate of half the samples,
    combined in quadrature.

    The drift is what the noise does not show: a pixel whose lobe the scene cuts rarely has
    traced nothing yet, so its difference and its noise read zero, and the estimate is off
    there until a sample finds the cut. Such a bias falls as 1 / samples, so the change of the
    median error since half the samples is about what is left of it (and more, with the
    half's noise in it). Where it falls slower (a diffuse term, which nearly every pixel of a
    self-occluding mesh traces) the drift reads short of it: on the bunny at k_d = 0.3 the
    errors at 64 samples were up to 2.7 times the uncertainty off those at 3642, hence the
    factor (studies/exact-reference/README.md, "The median's standard error").

    No rule on the samples' own statistics sees a bright path none has drawn: before the
    traced paths sampled the environment at every hit (shaders/reference/paths.glsl), the
    studio knot at N = 10 stopped at 64 samples with parallax's error 49 % off, and the
    coherent spread (every pixel moved by its noise at once) was kept as a floor. With them
    it stops at 251 samples within 1.6 % of the errors at 5335
    (studies/exact-reference/README.md, "Next-event estimation").

    Parameters
    ----------
    hdr, reference_hdr, pixel_noise, mask
        As :func:`median_error_uncertainty`.
    half_hdr : (h, w, 3) float32 or None
        The control-variate estimate from the first half of the samples (or fewer); None
        before there is one (the drift is then unknown: inf).

    Returns
    -------
    float
        Unitless, ≥ 0.
    """
    if half_hdr is None:
        return math.inf
    drift = median_error(hdr, reference_hdr, mask) - median_error(hdr, half_hdr, mask)
    noise = median_error_uncertainty(hdr, reference_hdr, pixel_noise, mask)
    return CONFIDENCE * float(math.hypot(noise, drift))


class ReferenceJudge:
    """Judges the methods' errors against the reference as it accumulates.

    Parameters
    ----------
    rule : str
        :data:`NOISE_RULE` or :data:`TOLERANCE_RULE`; under the tolerance rule
        the judgements are shown but never stop the reference.
    frames : dict
        Method name → its linear HDR frame, (h, w, 3) float32 (the reference excluded).

    Attributes
    ----------
    last : Judgement or None
        The latest judgement.
    """

    def __init__(self, rule: str, frames: dict[str, npt.NDArray[np.float32]]):
        self.rule = rule
        self.frames = frames
        self.last: Judgement | None = None
        self._before_last: Judgement | None = None
        self._first: Judgement | None = None
        self._judged_at = -math.inf

    def due(self, batches: int) -> bool:
        """Whether to judge after the reference's frame at ``batches``.

        At the first frame, at checkpoints, and when :data:`JUDGE_INTERVAL_S`
        has passed; never twice at one batch count.
        """
        if not self.frames or (self.last is not None and self.last.batches == batches):
            return False
        waited = time.perf_counter() - self._judged_at >= JUDGE_INTERVAL_S
        return self.last is None or is_checkpoint(batches) or waited

    def judge(
        self,
        reference: GroundTruth,
        reference_hdr: npt.NDArray[np.float32],
        mask: npt.NDArray[np.bool_],
        noise: float | None = None,
        pixel_noise: npt.NDArray | None = None,
        half_hdr: npt.NDArray[np.float32] | None = None,
    ) -> Judgement:
        """Measure the noise and every method's error against ``reference_hdr`` over ``mask``;
        ``noise``, when given, is the noise of ``reference_hdr`` (a control-variate estimate's),
        else the reference's own; ``pixel_noise`` (h, w), when given, its relative standard
        error per pixel and ``half_hdr`` the estimate of half its samples, which each method's
        :func:`control_variate_uncertainty` is judged by."""
        status = reference.status
        uncertainties = None
        if pixel_noise is not None:
            uncertainties = {
                name: control_variate_uncertainty(hdr, reference_hdr, pixel_noise, mask, half_hdr)
                for name, hdr in self.frames.items()
            }
        judgement = Judgement(
            batches=status.batches,
            samples=status.samples,
            seconds=status.run_elapsed(),
            noise=reference.relative_standard_error() if noise is None else noise,
            errors={
                name: median_error(hdr, reference_hdr, mask) for name, hdr in self.frames.items()
            },
            uncertainties=uncertainties,
        )
        self.record(judgement)
        return judgement

    def record(self, judgement: Judgement) -> None:
        """Make ``judgement`` the latest (the first one sets the start of the rate)."""
        self._before_last = self.last
        self.last = judgement
        if self._first is None:
            self._first = judgement
        self._judged_at = time.perf_counter()

    def satisfied(self) -> bool:
        """The noise rule holds for every method (never under the tolerance rule): at the
        latest judgement, and at the one before for a method within :data:`MARGIN` of its
        limit."""
        last = self.last
        return (
            self.rule == NOISE_RULE
            and last is not None
            and last.batches >= MIN_JUDGED_BATCHES
            and last.all_reliable
            and all(self._confirmed(name) for name in last.errors)
        )

    def _confirmed(self, name: str) -> bool:
        """Method ``name`` is under :data:`MARGIN` of its limit, or was reliable at the
        judgement before as well (one that could have stopped the reference itself)."""
        last, before = self.last, self._before_last
        if last.uncertainty(name) < MARGIN * NOISE_SHARE * last.errors[name]:
            return True
        return before is not None and before.batches >= MIN_JUDGED_BATCHES and before.reliable(name)

    def seconds_left(self) -> float | None:
        """Projected seconds until every method is reliable.

        Noise ∝ 1/sqrt(samples): the samples needed are samples ×
        :attr:`Judgement.shortfall`²; the rate is this run's samples per second between
        the first judgement and the last. None without a rate or a finite shortfall.
        """
        first, last = self._first, self.last
        if last is None or not math.isfinite(last.shortfall):
            return None
        needed = last.samples * last.shortfall**2
        if needed <= last.samples:
            return 0.0
        spent = last.seconds - first.seconds
        if last.samples <= first.samples or spent <= 0:
            return None
        rate = (last.samples - first.samples) / spent
        return (needed - last.samples) / rate

    def progress_line(self) -> str:
        """The noise, each method's error (✓ when reliable) and the projected time left."""
        last = self.last
        if last is None:
            return ""
        noise = f"{100 * last.noise:.3g} %" if math.isfinite(last.noise) else "—"
        if last.uncertainties is None:
            errors = ", ".join(
                f"{name} {100 * error:.3g} %{' ✓' if last.reliable(name) else ''}"
                for name, error in last.errors.items()
            )
            line = f"noise {noise} (needs < {100 * last.target:.3g} %); errors: {errors}"
        else:
            errors = ", ".join(
                f"{name} {100 * error:.3g} ± {100 * last.uncertainties[name]:.2g} %"
                f"{' ✓' if last.reliable(name) else ''}"
                for name, error in last.errors.items()
            )
            line = f"noise {noise} where traced; errors: {errors}"
        left = self.seconds_left()
        if self.rule == NOISE_RULE and left is not None:
            since = time.perf_counter() - self._judged_at
            line += f"; ≈ {duration(left - since)} to go"
        return line
