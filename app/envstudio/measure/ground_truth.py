"""The ground truth's protocol and the arithmetic of a progressive estimate.

``compare`` and ``bench --converge`` measure against one method, the plugin
declared ``ground_truth`` (:func:`envstudio.engine.registry.ground_truth_class`,
the shipped ``reference``), through :class:`GroundTruth` alone. It accumulates
batches, keeps a :class:`ConvergenceStatus`, checks its successive-half change
at the batch counts :func:`is_checkpoint` picks, and its saved accumulations
are keyed by what it declares it depends on (measure/ground_truth_cache.py).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import numpy.typing as npt

from envstudio.core.parameters import ParameterValues

#: The projection fits the checks whose samples are within this factor of the last.
FIT_SPAN = 10.0
FLATTEST_SLOPE = -0.1
#: Largest ``time_limit``, s (11.6 days).
MAX_TIME_LIMIT_S = 1e6


@dataclass
class ConvergenceStatus:
    """Where the accumulation stands.

    Attributes
    ----------
    batches : int
        Frames accumulated since the last restart.
    samples : int
        Estimates per pixel (batches × samples per batch).
    rms_change : float or None
        RMS(I_n − I_{n/2}) / RMS(I_n) at the last check (None before the first).
    checked_samples : int
        ``samples`` at that check (0 before it).
    converged : bool
        ``rms_change`` is below the tolerance.
    checks : list of dict
        Every check since the restart: ``samples``, ``change`` and
        ``seconds`` (wall time since ``started``).
    started : float
        ``time.perf_counter()`` at the restart.
    run_started : float
        ``time.perf_counter()`` when this process started (or resumed) the
        accumulation: ``time_limit`` counts from here.
    noise : float or None
        Median relative standard error over the reflector at ``noise_samples``
        (:func:`median_relative_error`; None before it is measured).
    noise_samples : int
        ``samples`` when ``noise`` was measured (-1 before).
    noise_at : float
        ``time.perf_counter()`` when ``noise`` was measured.
    """

    batches: int = 0
    samples: int = 0
    rms_change: float | None = None
    checked_samples: int = 0
    converged: bool = False
    checks: list[dict] = field(default_factory=list)
    started: float = field(default_factory=time.perf_counter)
    run_started: float = field(default_factory=time.perf_counter)
    noise: float | None = None
    noise_samples: int = -1
    noise_at: float = 0.0

    def elapsed(self) -> float:
        """Wall seconds since ``started`` (a resumed run counts its earlier runs' time)."""
        return time.perf_counter() - self.started

    def run_elapsed(self) -> float:
        """Wall seconds since ``run_started`` (this process's part of the accumulation)."""
        return time.perf_counter() - self.run_started

    def describe(self) -> str:
        """One line for the UI and the CLI."""
        change = "—" if self.rms_change is None else f"{100 * self.rms_change:.3f} %"
        state = "converged" if self.converged else "converging"
        noise = ""
        if self.noise is not None:
            value = f"{100 * self.noise:.3g} %" if math.isfinite(self.noise) else "—"
            noise = f", noise {value}"
        return f"{self.samples} spp{noise}, half-change {change}: {state}"


#: The ground truth's bool parameter that turns on what no environment map shows.
SCENE_EFFECTS = "trace"
#: Its bool parameter that, with scene effects on, gives the untraced estimate too.
UNTRACED_TOO = "untraced_too"


@dataclass(frozen=True)
class PairedEstimates:
    """The traced and untraced estimates of one accumulation, from the same samples.

    Every array is (h, w, 3) float32, row 0 at the top; the errors are standard errors of the
    means from the spread of the batch means (inf before two batches).

    Attributes
    ----------
    traced, traced_error
        The reference as traced, and its error.
    untraced, untraced_error
        The untraced model's estimate from the same sample directions, and its error.
    difference_error
        The error of traced − untraced (from the spread of each batch's difference): with
        the other two, their covariance.
    """

    traced: npt.NDArray[np.float32]
    traced_error: npt.NDArray[np.float32]
    untraced: npt.NDArray[np.float32]
    untraced_error: npt.NDArray[np.float32]
    difference_error: npt.NDArray[np.float32]

    def controlled(
        self, exact: npt.NDArray[np.float32]
    ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """The traced estimate with the untraced one as its control variate.

        With the untraced model known exactly (``exact``, (h, w, 3)), T − β (U − exact) has
        T's expectation for any β, and the least variance at β = Cov(T, U) / Var(U), per pixel
        and channel: Var(T) (1 − ρ²), never more than T's own. Cov is
        (Var T + Var U − Var(T − U)) / 2 from the three errors. β is clipped to [0, 2]
        (estimated from the same batches, it is noisy where they are few). Where nothing is
        traced T = U and β = 1: the exact value, no noise; where local objects hide the map
        T and U hardly vary together and β → 0: the plain traced estimate.

        Returns
        -------
        estimate, error : (h, w, 3) float32
        """
        errors = (self.traced_error, self.untraced_error, self.difference_error)
        finite = np.logical_and.reduce([np.isfinite(e) for e in errors])
        t2, u2, d2 = (np.where(finite, e, 0.0).astype(np.float64) ** 2 for e in errors)
        covariance = 0.5 * (t2 + u2 - d2)
        beta = np.divide(covariance, u2, out=np.ones_like(u2), where=u2 > 0)
        beta = np.clip(beta, 0.0, 2.0)
        estimate = self.traced - beta * (self.untraced - exact)
        variance = np.maximum(t2 - 2.0 * beta * covariance + beta**2 * u2, 0.0)
        error = np.where(finite, np.sqrt(variance), np.inf)
        return estimate.astype(np.float32), error.astype(np.float32)


class GroundTruth(Protocol):
    """What ``compare``, its stopping rule and its cache use of the ground-truth method.

    Besides the :class:`~envstudio.engine.method.Method` contract: parameters
    ``samples``, ``max_samples``, ``tolerance`` and ``time_limit``, and
    :data:`SCENE_EFFECTS`, on when it renders what no environment map shows
    (self-occlusion, interreflection) and off for the environment-map model itself,
    and :data:`UNTRACED_TOO`, which with scene effects on also accumulates the
    environment-map model's estimate from the same samples (:meth:`untraced_estimate`).
    """

    name: str
    #: The reflectance models its ``model`` parameter renders.
    models: tuple[str, ...]
    values: ParameterValues
    status: ConvergenceStatus

    def finished(self) -> bool:
        """Converged, or stopped by its budget."""

    def stop_reason(self) -> str | None:
        """``converged``, ``max_samples`` or ``time_limit`` (None while running)."""

    def status_line(self) -> str:
        """One line of progress."""

    def traces_anything(self) -> bool:
        """Whether :data:`SCENE_EFFECTS` can change the estimate with the current values
        (False: the traced estimate is the untraced one, nothing to sample)."""

    def relative_standard_error(self) -> float:
        """Median relative standard error over the reflector (the noise)."""

    def coverage(self) -> npt.NDArray[np.bool_]:
        """(h, w) pixels the estimate covers (row 0 at the top)."""

    def untraced_estimate(self) -> npt.NDArray[np.float32] | None:
        """(h, w, 3) the untraced estimate of the same samples (:data:`UNTRACED_TOO`), or None."""

    def untraced_relative_standard_error(self) -> float:
        """Its noise, as :meth:`relative_standard_error`."""

    def paired(self) -> PairedEstimates | None:
        """The traced and untraced estimates of the same samples with their errors and the
        error of their difference, or None without :data:`UNTRACED_TOO`."""

    def accumulation_state(self) -> dict[str, npt.NDArray]:
        """The accumulation as arrays, to save."""

    def resume(self, state: dict[str, npt.NDArray]) -> None:
        """Continue from a saved state at the next frame."""

    def saved_samples(self, state: dict[str, npt.NDArray]) -> int:
        """Samples per pixel a saved state holds."""

    def cache_identity(self) -> list[bytes]:
        """What the estimate depends on besides the scene, camera and size: its
        parameters (those that only schedule it left out) and its shaders' text."""


def is_checkpoint(batches: int) -> bool:
    """Whether the estimate is kept (and checked against half the batches) at ``batches``.

    Checkpoints are 2, 3 and c 2^k for c in 4 … 7: four per doubling, each
    with its half among them (even ones), so the check runs at most a quarter
    octave after the change first falls below the tolerance, not a whole one.
    """
    return batches >= 2 and batches & ((1 << max(batches.bit_length() - 3, 0)) - 1) == 0


def project_convergence(checks: list[dict], tolerance: float) -> dict | None:
    """Samples and seconds to reach ``tolerance``, extrapolated from the last checks.

    Fits log(change) = a + s log(samples) by least squares over the checks
    whose samples are within :data:`FIT_SPAN` of the last (the last four
    where checks came at doublings; s = −1/2 for plain Monte Carlo, steeper
    for the Sobol sequence on smooth integrands), and the time per sample over
    the same span.

    Parameters
    ----------
    checks : list of dict
        ``samples``, ``change`` and ``seconds`` at successive checks
        (:attr:`ConvergenceStatus.checks`).
    tolerance : float
        The relative half-change to reach.

    Returns
    -------
    dict or None
        ``slope`` s, ``samples`` and ``seconds`` (since the start) at which
        the fitted change reaches the tolerance; None with fewer than two
        checks or a slope flatter than :data:`FLATTEST_SLOPE`.
    """
    tail = [c for c in checks if c["samples"] * FIT_SPAN >= checks[-1]["samples"]] if checks else []
    if len(tail) < 2:
        return None
    log_n = np.log([c["samples"] for c in tail])
    log_change = np.log([c["change"] for c in tail])
    slope, intercept = np.polyfit(log_n, log_change, 1)
    if slope > FLATTEST_SLOPE:
        return None
    samples = math.exp((math.log(tolerance) - intercept) / slope)
    span = tail[-1]["samples"] - tail[0]["samples"]
    per_sample = (tail[-1]["seconds"] - tail[0]["seconds"]) / span
    return {
        "slope": float(slope),
        "samples": samples,
        "seconds": tail[-1]["seconds"] + (samples - tail[-1]["samples"]) * per_sample,
    }


def duration(seconds: float) -> str:
    """``12 s``, ``5 min``, ``2.5 h``."""
    if seconds < 120:
        return f"{max(seconds, 0):.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.3g} h"
