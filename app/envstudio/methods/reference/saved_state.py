"""The accumulation as arrays: saved to the cache, resumed from (measure/ground_truth_cache.py).

Keys: ``sum``, ``sum_sq`` ((h, w, 4) float32, row 0 at the top),
``batches``, ``checked_samples`` (int64), ``rms_change`` (float64, NaN
before the first check), ``snapshots`` ((k, h, w, 3) float32 estimates at the
checkpoints later checks compare with) and ``snapshot_batches`` ((k,) int64,
their batch counts), ``checks`` ((k, 3) float64: samples, change, seconds of
every check), ``seconds`` (float64 wall time spent accumulating, over all the
runs that built it), the sample allocation (:meth:`SampleAllocation.as_arrays`)
and, with ``untraced_too``, ``untraced_sum`` and ``untraced_sum_sq`` (as
``sum`` and ``sum_sq``).
"""

from __future__ import annotations

import time

import numpy as np
import numpy.typing as npt

from envstudio.methods.reference.accumulation import Accumulation
from envstudio.methods.reference.convergence import Convergence
from envstudio.methods.reference.sample_allocation import SampleAllocation

SavedState = dict[str, npt.NDArray]


def accumulation_state(accumulation: Accumulation, convergence: Convergence) -> SavedState:
    """The accumulation and its convergence as the arrays of this module's keys."""
    total, squares = accumulation.read()
    status = convergence.status
    change = status.rms_change
    checks = [[c["samples"], c["change"], c["seconds"]] for c in status.checks]
    untraced = accumulation.read_untraced()
    untraced_sums = (
        {} if untraced is None else {"untraced_sum": untraced[0], "untraced_sum_sq": untraced[1]}
    )
    return {
        "sum": total,
        "sum_sq": squares,
        "batches": np.int64(status.batches),
        "checked_samples": np.int64(status.checked_samples),
        "rms_change": np.float64(np.nan if change is None else change),
        "snapshots": np.asarray(list(convergence.snapshots.values()), np.float32).reshape(
            -1, *total.shape[:2], 3
        ),
        "snapshot_batches": np.asarray(list(convergence.snapshots), np.int64),
        "checks": np.asarray(checks, np.float64).reshape(-1, 3),
        "seconds": np.float64(status.elapsed()),
        **accumulation.allocation.as_arrays(),
        **untraced_sums,
    }


def saved_samples(state: SavedState, samples: int) -> int:
    """Samples per pixel ``state`` holds, drawn at ``samples`` per pixel and batch (× m)."""
    batches = int(state["batches"])
    allocation = SampleAllocation.from_arrays(state, state["sum"].shape[:2], batches)
    return allocation.samples_per_pixel(batches, samples)


def restore(
    state: SavedState, accumulation: Accumulation, convergence: Convergence, samples: int
) -> None:
    """Continue ``accumulation`` and ``convergence`` from ``state``, as if its batches had been
    drawn here at ``samples`` per pixel and batch; a state of another size is ignored."""
    w, h = accumulation.size
    shape = (h, w, 4)
    if state["sum"].shape != shape or state["sum_sq"].shape != shape:
        return
    untraced = (
        (state["untraced_sum"], state["untraced_sum_sq"]) if "untraced_sum" in state else None
    )
    accumulation.write_sums(state["sum"], state["sum_sq"], untraced)
    batches = int(state["batches"])
    change = float(state["rms_change"])
    status = convergence.status
    status.batches = batches
    accumulation.set_allocation(SampleAllocation.from_arrays(state, (h, w), batches))
    status.samples = accumulation.allocation.samples_per_pixel(batches, samples)
    status.checked_samples = int(state["checked_samples"])
    if not np.isnan(change):
        status.rms_change = change
        convergence.judge()
    convergence.snapshots = _saved_snapshots(state, batches)
    checks = state.get("checks", np.zeros((0, 3)))
    status.checks = [
        {"samples": int(n), "change": float(change), "seconds": float(seconds)}
        for n, change, seconds in checks
    ]
    status.started = time.perf_counter() - float(state.get("seconds", 0.0))


def _saved_snapshots(state: SavedState, batches: int) -> dict[int, npt.NDArray[np.float32]]:
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
