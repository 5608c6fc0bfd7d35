"""``envstudio bench --converge``: time for the reference to reach its tolerance.

The reference checks the successive-half change at every doubling of its batch
count (methods/reference.py); this records each check with the wall time since
the first frame, stops at convergence, at the sample budget or at a time limit,
and, where it stopped short, projects the samples and time the tolerance would
take from the slope of log(change) against log(samples) over the last checks
(-1/2 for plain Monte Carlo, steeper for the Sobol sequence).
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np
from tqdm import tqdm

from envstudio.gpu.context import describe
from envstudio.methods.reference import ReferenceMethod
from envstudio.render.session import RenderSession

FIT_CHECKS = 4
FLATTEST_SLOPE = -0.1


def run_convergence(
    session: RenderSession,
    method: ReferenceMethod,
    size: tuple[int, int],
    time_limit_s: float,
    progress: bool = True,
) -> dict:
    """Accumulate ``method`` until it converges, spends its budget or runs out of time.

    Parameters
    ----------
    session : RenderSession
        Holds the scene and the camera.
    method : ReferenceMethod
        With its parameters (tolerance, max_samples, …) already set.
    size : (int, int)
        Frame width and height in pixels.
    time_limit_s : float
        Wall-clock limit in seconds.
    progress : bool
        Show a bar with the latest change on stderr.

    Returns
    -------
    dict
        JSON-ready: device, size, parameters, ``checks`` (samples, change,
        seconds at each doubling), converged, seconds, samples, and
        ``projection`` (slope, samples and seconds to the tolerance) when it
        stopped short with at least two checks.
    """
    tolerance = float(method.values["tolerance"])
    checks: list[dict] = []
    session.ctx.finish()
    start = time.perf_counter()
    with tqdm(
        desc="reference",
        unit="frame",
        file=sys.stderr,
        disable=not progress,
        bar_format="{desc}: {n} frames {elapsed} {postfix}",
    ) as bar:
        while True:
            session.render_offscreen(method, size)
            session.ctx.finish()
            elapsed = time.perf_counter() - start
            bar.update(1)
            status = method.status
            if status.checked_samples and (
                not checks or checks[-1]["samples"] != status.checked_samples
            ):
                checks.append(
                    {"samples": status.samples, "change": status.rms_change, "seconds": elapsed}
                )
                bar.set_postfix_str(method.status_line())
            if method.finished() or elapsed >= time_limit_s:
                break
    report = {
        "device": describe(session.ctx),
        "size": list(size),
        "parameters": method.values.as_dict(),
        "tolerance": tolerance,
        "checks": checks,
        "converged": method.status.converged,
        "samples": method.status.samples,
        "seconds": elapsed,
    }
    if not method.status.converged:
        report["projection"] = project(checks, tolerance)
    return report


def project(checks: list[dict], tolerance: float) -> dict | None:
    """Samples and seconds to reach ``tolerance``, extrapolated from the last checks.

    Fits log(change) = a + s log(samples) by least squares over the last
    :data:`FIT_CHECKS` checks, and the time per sample over the same span.

    Returns
    -------
    dict or None
        ``slope`` s, ``samples`` and ``seconds`` at which the fitted change
        reaches the tolerance; None with fewer than two checks or a slope
        flatter than :data:`FLATTEST_SLOPE` (no meaningful projection).
    """
    tail = checks[-FIT_CHECKS:]
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
    return {"slope": float(slope), "samples": samples, "seconds": samples * per_sample}


def format_convergence(report: dict) -> str:
    """A plain-text table of a convergence report."""
    lines = [
        f"device: {report['device']}  size: {report['size'][0]}x{report['size'][1]}  "
        f"tolerance: {100 * report['tolerance']:.3g} %",
        f"{'spp':>9} {'half-change':>12} {'seconds':>10}",
    ]
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
