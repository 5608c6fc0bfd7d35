"""``envstudio bench --converge``: time for the ground truth to reach its tolerance.

The ground truth (the shipped reference) checks the successive-half change at
every doubling of its batch count and records each check with its wall time
(measure/ground_truth.py's :class:`ConvergenceStatus`); this
renders it until it converges, spends its sample budget or reaches a time
limit, and, where it stopped short, reports the samples and time the tolerance
would take, projected from the slope of log(change) against log(samples) over
the last checks (:func:`~envstudio.measure.ground_truth.project_convergence`).
"""

from __future__ import annotations

import contextlib
import sys
import time

from tqdm import tqdm

from envstudio.engine.session import RenderSession
from envstudio.gpu.context import describe
from envstudio.measure.ground_truth import GroundTruth, project_convergence
from envstudio.measure.ground_truth_cache import Checkpoint


def run_convergence(
    session: RenderSession,
    method: GroundTruth,
    size: tuple[int, int],
    time_limit_s: float,
    progress: bool = True,
    resume: bool = False,
) -> dict:
    """Accumulate ``method`` until it converges, spends its budget or runs out of time.

    Parameters
    ----------
    session : RenderSession
        Holds the scene and the camera.
    method : GroundTruth
        With its parameters (tolerance, max_samples, …) already set.
    size : (int, int)
        Frame width and height in pixels.
    time_limit_s : float
        Wall-clock limit in seconds.
    progress : bool
        Show a bar with the latest change on stderr.
    resume : bool
        Continue the accumulation saved by an earlier run with the same inputs
        (measure/ground_truth_cache.py) and save this one every minute and at the
        end; the checks and seconds then count every run that built it.

    Returns
    -------
    dict
        JSON-ready: device, size, parameters, ``checks`` (samples, change,
        seconds at each doubling), converged, ``seconds`` (all runs),
        ``run_seconds`` (this run), ``resumed_samples``, samples, and
        ``projection`` (slope, samples and seconds to the tolerance) when it
        stopped short with at least two checks.
    """
    tolerance = float(method.values["tolerance"])
    checkpoint = Checkpoint(session, method, size) if resume else None
    session.ctx.finish()
    start = time.perf_counter()
    with (
        tqdm(
            desc=method.name,
            unit="frame",
            file=sys.stderr,
            disable=not progress,
            bar_format="{desc}: {n} frames {elapsed} {postfix}",
        ) as bar,
        checkpoint.saved_on_interrupt() if checkpoint else contextlib.nullcontext(),
    ):
        while True:
            session.render_offscreen(method, size)
            session.ctx.finish()
            elapsed = time.perf_counter() - start
            bar.update(1)
            bar.set_postfix_str(method.status_line())
            if method.finished() or elapsed >= time_limit_s:
                break
            if checkpoint:
                checkpoint.save_if_due()
    if checkpoint:
        checkpoint.save()
    checks = method.status.checks
    report = {
        "device": describe(session.ctx),
        "size": list(size),
        "parameters": method.values.as_dict(),
        "tolerance": tolerance,
        "checks": checks,
        "converged": method.status.converged,
        "samples": method.status.samples,
        "seconds": method.status.elapsed(),
        "run_seconds": elapsed,
        "resumed_samples": checkpoint.resumed_samples if checkpoint else 0,
    }
    if not method.status.converged:
        report["projection"] = project_convergence(checks, tolerance)
    return report


def format_convergence(report: dict) -> str:
    """A plain-text table of a convergence report."""
    lines = [
        f"device: {report['device']}  size: {report['size'][0]}x{report['size'][1]}  "
        f"tolerance: {100 * report['tolerance']:.3g} %",
        f"{'spp':>9} {'half-change':>12} {'seconds':>10}",
    ]
    if report["resumed_samples"]:
        lines[0] += f"  (resumed at {report['resumed_samples']} spp)"
    for check in report["checks"]:
        lines.append(
            f"{check['samples']:>9} {100 * check['change']:>11.4f}% {check['seconds']:>10.1f}"
        )
    if report["converged"]:
        lines.append(f"converged: {report['samples']} spp in {report['seconds']:.1f} s")
        return "\n".join(lines)
    lines.append(f"NOT converged: {report['samples']} spp in {report['seconds']:.1f} s")
    projection = report.get("projection")
    if projection:
        lines.append(
            f"projected (slope {projection['slope']:.2f}): {projection['samples']:.3g} spp, "
            f"{projection['seconds']:.3g} s"
        )
    return "\n".join(lines)
