"""When the reference stops: the successive-half criterion, the sample and time budgets.

Four times per doubling of the batch count n (:func:`is_checkpoint`) the
estimate I_n is compared with I_{n/2}; the accumulation is converged when
RMS(I_n − I_{n/2}) / RMS(I_n) over the covered pixels falls below
``tolerance``. It also stops on ``max_samples`` or ``time_limit``, both
reported as not converged.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from envstudio.plugin import ConvergenceStatus, ParameterValues, duration, project_convergence

#: Seconds between measurements of the noise shown in the status line (a GPU read each).
NOISE_REFRESH_S = 2.0
#: Batches before the time limit may stop the accumulation (a standard error needs two).
MIN_TIMED_BATCHES = 2


class Convergence:
    """The state of one accumulation's convergence and the verdicts drawn from it.

    Parameters
    ----------
    values : ParameterValues
        The method's parameters: ``tolerance``, ``max_samples`` and
        ``time_limit`` are read whenever a verdict is drawn.

    Attributes
    ----------
    status : ConvergenceStatus
        Batches, samples per pixel, checks and the verdict.
    snapshots : dict of int to (h, w, 3) float32
        Estimates (radiance) at earlier checkpoints, by batch count, until no
        check needs them.
    """

    def __init__(self, values: ParameterValues):
        self.values = values
        self.status = ConvergenceStatus()
        self.snapshots: dict[int, npt.NDArray[np.float32]] = {}

    def restart(self) -> None:
        """Forget every batch and check: a new accumulation."""
        self.status = ConvergenceStatus()
        self.snapshots = {}

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

    def check(self, estimate: npt.NDArray[np.float32], covered: npt.NDArray[np.bool_]) -> None:
        """At a checkpoint: keep ``estimate``, compare it with the one at half the batches.

        Parameters
        ----------
        estimate : (h, w, 3) float32
            The mean radiance now.
        covered : (h, w) bool
            The pixels compared.
        """
        status = self.status
        batches = status.batches
        half = self.snapshots.get(batches // 2) if batches % 2 == 0 else None
        if half is not None and covered.any():
            now = estimate[covered].astype(np.float64)
            diff = now - half[covered]
            norm = np.sqrt(np.mean(now**2))
            # an all-black estimate has not converged to anything: never call it converged
            change = float(np.sqrt(np.mean(diff**2)) / norm) if norm > 0 else float("inf")
            status.rms_change = change
            status.checked_samples = status.samples
            status.checks.append(
                {"samples": status.samples, "change": change, "seconds": status.elapsed()}
            )
            self.judge()
        # later checks compare with later halves
        self.snapshots = {b: e for b, e in self.snapshots.items() if b > batches // 2}
        self.snapshots[batches] = estimate

    def judge(self) -> None:
        """Converged: the last check's change is below the current tolerance."""
        change = self.status.rms_change
        self.status.converged = change is not None and change < float(self.values["tolerance"])

    def refresh_noise(self, measure: Callable[[], float]) -> None:
        """Set the status's noise from ``measure()`` (a GPU read): when there are new samples,
        and the accumulation stopped or :data:`NOISE_REFRESH_S` passed since the last time."""
        status = self.status
        if status.samples == status.noise_samples:
            return
        if self.stop_reason() is None and time.perf_counter() - status.noise_at < NOISE_REFRESH_S:
            return
        status.noise = measure()
        status.noise_samples = status.samples
        status.noise_at = time.perf_counter()

    def describe(self) -> str:
        """Samples, noise, the last half-change, the state, and the projected time left."""
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
