"""``envstudio bench --prefilter``: seed 004 §5.1's table and its linear/sublinear claim.

The table (§5.1, "Results"): a Phong-prefiltered dual paraboloid map of 2 × S × S
texels (S = 128: the paper's 128×256) from a 2S × S lat-long source, brute
force against the hierarchical method at threshold 0.001, for each exponent:
both times in the same run (each the best of three, alternating), their ratio
and the largest difference between the two maps relative to the brute-force
map's mean (all texels, all channels).

The sweep: "the brute force method has linear complexity in the number of
touched pixels, whereas our hierarchical method is sublinear". Face sizes 64²
to 512² with sources of matching size (so the pairs grow 16× per step); where
a full map would take long, a stratified sample of target texels (brute:
every k-th texel; hierarchical: every k-th band of tiles, from the middle of
the first k) is timed and scaled by k, which is exact for the brute force
(the same work per texel) and an estimate for the hierarchical method. The plot is time against
touched pixel pairs (target × source texels), log–log.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import numpy.typing as npt

from envstudio.io.atomic import atomic_path
from envstudio.prefilter import brute_force, hierarchical, kernels
from envstudio.prefilter.chain import chain_level_error
from envstudio.prefilter.parallel import default_threads
from envstudio.prefilter.targets import target_directions

__all__ = [
    "CMFT_SECONDS",
    "PAPER_TABLE",
    "SWEEP_EXPONENT",
    "SWEEP_FACES",
    "format_chain_report",
    "format_prefilter_report",
    "run_chain_bench",
    "run_prefilter_bench",
    "write_scaling_plot",
]

#: Seed 004 §5.1 (Pentium II 350 MHz): exponent → (brute force s, hierarchical s, speed-up).
PAPER_TABLE = {
    10: (413.0, 98.0, 4.2),
    50: (442.0, 83.0, 5.3),
    100: (474.0, 61.0, 7.7),
    250: (545.0, 55.0, 9.9),
    500: (552.0, 39.0, 14.1),
}
#: Face sizes of the time-against-size sweep, and its Phong exponent.
SWEEP_FACES = (64, 128, 256, 512)
SWEEP_EXPONENT = 100.0
# Pairs (target × source texels) timed per point of the sweep at most; beyond, a sample.
_SWEEP_BRUTE_PAIRS = 2**30
_SWEEP_HIERARCHICAL_PAIRS = 2**34
_TILE = 8


def run_prefilter_bench(
    radiance: npt.ArrayLike,
    face: int,
    exponents: Sequence[float],
    *,
    threshold: float = hierarchical.DEFAULT_THRESHOLD,
    sweep: Sequence[int] = SWEEP_FACES,
    repeats: int = 3,
    threads: int | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """Time both prefilters at each exponent, then the sweep over sizes.

    Parameters
    ----------
    radiance
        (h, 2h, 3) lat-long radiance; box-filtered to each source size, so h must
        be a multiple of ``face`` and of every sweep size.
    face
        Paraboloid face edge S of the table (the source is 2S × S).
    exponents
        Phong exponents N of the table.
    threshold
        The hierarchical method's T.
    sweep
        Face sizes of the sweep (empty: none).
    repeats
        Runs of each method per exponent, alternating; the fastest counts (the
        machine is shared: the least disturbed run is the best estimate).
    threads
        Worker threads (default: every core).
    progress
        Called with one line before each measurement.

    Returns
    -------
    dict
        JSON-ready: the settings, ``rows`` (one per exponent) and ``sweep``.
    """
    threads = threads or default_threads()
    say = progress or (lambda line: None)
    source = brute_force.downsample_latlong(radiance, face)
    directions = target_directions("paraboloid", face)
    pyramid = hierarchical.source_pyramid(source)
    rows = []
    for exponent in exponents:
        kernel = kernels.phong(float(exponent))
        brute_times, hier_times = [], []
        for run in range(repeats):
            say(f"N = {exponent:g}: brute force, run {run + 1}/{repeats}")
            brute, seconds = _timed(
                lambda k=kernel: brute_force.prefilter(source, directions, k, threads=threads)
            )
            brute_times.append(seconds)
            say(f"N = {exponent:g}: hierarchical, run {run + 1}/{repeats}")
            hier, seconds = _timed(
                lambda k=kernel: hierarchical.prefilter(
                    pyramid, directions, k, threshold, tile=_TILE, threads=threads
                )
            )
            hier_times.append(seconds)
        brute_s, hier_s = min(brute_times), min(hier_times)
        mean = float(brute.mean())
        paper = PAPER_TABLE.get(int(exponent)) if float(exponent).is_integer() else None
        rows.append(
            {
                "exponent": float(exponent),
                "brute_s": brute_s,
                "hierarchical_s": hier_s,
                "brute_runs_s": brute_times,
                "hierarchical_runs_s": hier_times,
                "speedup": brute_s / hier_s,
                "max_difference_over_mean": float(np.abs(hier - brute).max() / mean),
                "rms_difference_over_mean": float(np.sqrt(np.mean((hier - brute) ** 2)) / mean),
                "paper": None
                if paper is None
                else {"brute_s": paper[0], "hierarchical_s": paper[1], "speedup": paper[2]},
            }
        )
    points = [_sweep_point(radiance, n, threshold, threads, say) for n in sweep]
    slopes = {key: _slope(points, key) for key in ("brute_s", "hierarchical_s")}
    return {
        "what": "seed 004 §5.1: Phong prefilter of a dual paraboloid map, brute force vs "
        "hierarchical",
        "target": f"paraboloid 2x{face}x{face} (the paper's {face}x{2 * face})",
        "source": f"lat-long {source.shape[1]}x{source.shape[0]}",
        "threshold": threshold,
        "threads": threads,
        "repeats": repeats,
        "cpu_count": os.cpu_count(),
        "load_average_at_start": list(os.getloadavg()),
        "rows": rows,
        "sweep_exponent": SWEEP_EXPONENT,
        "sweep": points,
        "sweep_slopes": slopes,
    }


def _slope(points: list[dict], key: str) -> float | None:
    """Least-squares slope of log(seconds) against log(pairs): 1 is linear, below 1 sublinear."""
    if len(points) < 2:
        return None
    x = np.log([p["pairs"] for p in points])
    return float(np.polyfit(x, np.log([p[key] for p in points]), 1)[0])


def _timed(run: Callable[[], np.ndarray]) -> tuple[np.ndarray, float]:
    start = time.perf_counter()
    result = run()
    return result, time.perf_counter() - start


def _sweep_point(radiance, face: int, threshold: float, threads: int, say) -> dict:
    """Brute and hierarchical seconds for one face size, sampled where large (module doc)."""
    source = brute_force.downsample_latlong(radiance, face)
    directions = target_directions("paraboloid", face)
    kernel = kernels.phong(SWEEP_EXPONENT)
    targets, texels = directions.size // 3, source.shape[0] * source.shape[1]
    pairs = targets * texels
    brute_stride = max(1, -(-pairs // _SWEEP_BRUTE_PAIRS))
    say(f"sweep {face}²: brute force on 1/{brute_stride} of the targets")
    _, brute_s = _timed(
        lambda: brute_force.prefilter(
            source, directions.reshape(-1, 3)[::brute_stride], kernel, threads=threads
        )
    )
    pyramid = hierarchical.source_pyramid(source)
    bands = face // _TILE
    band_stride = min(bands, max(1, -(-pairs // _SWEEP_HIERARCHICAL_PAIRS)))
    rows = np.concatenate(
        [np.arange(b * _TILE, (b + 1) * _TILE) for b in range(band_stride // 2, bands, band_stride)]
    )
    say(f"sweep {face}²: hierarchical on {len(rows)}/{face} rows")
    _, hier_s = _timed(
        lambda: hierarchical.prefilter(
            pyramid, directions[:, rows], kernel, threshold, tile=_TILE, threads=threads
        )
    )
    return {
        "face": face,
        "source": f"{source.shape[1]}x{source.shape[0]}",
        "pairs": pairs,
        "brute_s": brute_s * brute_stride,
        "brute_sampled": 1.0 / brute_stride,
        "hierarchical_s": hier_s * face / len(rows),
        "hierarchical_sampled": len(rows) / face,
    }


def format_prefilter_report(report: dict) -> str:
    """The table as text, with the paper's numbers beside ours."""
    lines = [
        f"{report['target']} from {report['source']}, threshold {report['threshold']:g}, "
        f"{report['threads']} threads (load {report['load_average_at_start'][0]:.1f})",
        f"{'N':>5} {'brute s':>8} {'hier s':>7} {'ratio':>6} {'max diff':>9} "
        f"{'| paper brute':>13} {'hier':>5} {'ratio':>6}",
    ]
    for row in report["rows"]:
        paper = row["paper"]
        theirs = (
            f"| {paper['brute_s']:>11.0f} {paper['hierarchical_s']:>5.0f} {paper['speedup']:>6.1f}"
            if paper
            else "|"
        )
        lines.append(
            f"{row['exponent']:>5g} {row['brute_s']:>8.2f} {row['hierarchical_s']:>7.2f} "
            f"{row['speedup']:>6.2f} {100 * row['max_difference_over_mean']:>8.3f}% {theirs}"
        )
    if report["sweep"]:
        slopes = report["sweep_slopes"]
        fitted = ", ".join(
            f"{name} {slopes[key]:.2f}"
            for name, key in (("brute", "brute_s"), ("hierarchical", "hierarchical_s"))
            if slopes.get(key) is not None
        )
        lines.append(
            f"time against size (N = {report['sweep_exponent']:g}; log-log slope: {fitted}):"
        )
        for p in report["sweep"]:
            lines.append(
                f"  2x{p['face']}² from {p['source']}: brute {p['brute_s']:.2f} s "
                f"(timed {100 * p['brute_sampled']:.3g} %), hierarchical "
                f"{p['hierarchical_s']:.2f} s (timed {100 * p['hierarchical_sampled']:.3g} %)"
            )
    return "\n".join(lines)


def write_scaling_plot(report: dict, path: str | os.PathLike) -> Path:
    """Time against touched pixel pairs, log–log, with a slope-1 guide (atomic PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    points = report["sweep"]
    pairs = np.array([p["pairs"] for p in points], dtype=np.float64)
    fig, ax = plt.subplots(figsize=(6, 4.2), dpi=120)
    slopes = report.get("sweep_slopes", {})
    for key, label, marker in (
        ("brute_s", "brute force", "o"),
        ("hierarchical_s", f"hierarchical (T = {report['threshold']:g})", "s"),
    ):
        slope = slopes.get(key)
        fitted = f", slope {slope:.2f}" if slope is not None else ""
        ax.loglog(pairs, [p[key] for p in points], marker=marker, label=label + fitted)
    middle = len(points) // 2
    anchor = points[middle]["brute_s"] / pairs[middle]
    ax.loglog(pairs, anchor * pairs, "k:", lw=1, label="linear in touched pixels (slope 1)")
    for p, x in zip(points, pairs, strict=True):
        ax.annotate(f"{p['face']}²", (x, p["brute_s"]), textcoords="offset points", xytext=(4, -12))
    ax.set_xlabel("touched pixel pairs (target texels × source texels)")
    ax.set_ylabel("seconds")
    ax.set_title(f"Phong N = {report['sweep_exponent']:g}, paraboloid 2×n² from 2n×n lat-long")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
    return path


#: Issue 14: cmft (phongbrdf filter, both cores) on this machine type, an 8-level chain.
CMFT_SECONDS = {128: 0.41, 256: 5.3}


def run_chain_bench(
    radiance: npt.ArrayLike,
    sizes: Sequence[int] = (128, 256),
    samples: int | None = None,
    repeats: int = 3,
    check: bool = True,
    gpu: bool = True,
) -> dict:
    """Time the CPU spectral chain and the GPU chain at each face size; with ``check``, errors.

    Parameters
    ----------
    radiance
        (h, 2h, 3) lat-long source.
    sizes
        Level-0 face edges; each chain has 8 levels, gloss scale 10 and bias 1.
    samples
        The GPU chain's level-0 samples (default prefilter.chain_gpu.DEFAULT_SAMPLES).
    repeats
        Each time is the best of this many runs. The GPU chain's come after one untimed
        run that compiles the program; the spectral chain's after one *cold* run, timed
        and reported apart, that builds its cached tables (prefilter.spectral.plan and
        the interpolation matrices), which depend on the source's shape and N only.
    check
        Also every level's RMS and max difference to the brute force
        (prefilter.chain.chain_level_error, 256 texels a level).
    gpu
        Also the GPU chain (prefilter.chain_gpu), when a GL context can be made.

    Returns
    -------
    dict
        ``spectral``: per size ``cold_seconds``, ``seconds`` (best warm wall), ``cpu_seconds``
        (its ``time.process_time``), ``runs``, cmft's seconds, the speed-up over them, and
        ``levels`` (face, N, rms, max); ``gpu``: the same for the GPU chain (no cold run,
        with ``renderer``, ``context_seconds``, ``samples``), or None without a context.
    """
    from envstudio.prefilter import spectral

    def levels_of(chain) -> list[dict]:
        return [
            {"face": level.faces.shape[1], "exponent": level.exponent}
            | dict(zip(("rms", "max"), chain_level_error(radiance, level), strict=True))
            for level in chain
        ]

    def timed(run: Callable[[], list]) -> tuple[list, float, float]:
        wall, cpu = time.perf_counter(), time.process_time()
        chain = run()
        return chain, time.perf_counter() - wall, time.process_time() - cpu

    def entry_for(size: int, runs: list[float], cpu: list[float], chain: list) -> dict:
        best = int(np.argmin(runs))
        entry = {"size": size, "seconds": runs[best], "cpu_seconds": cpu[best], "runs": runs}
        if size in CMFT_SECONDS:
            entry["cmft_seconds"] = CMFT_SECONDS[size]
            entry["speedup_over_cmft"] = CMFT_SECONDS[size] / runs[best]
        if check:
            entry["levels"] = levels_of(chain)
        return entry

    report = {"load_average": os.getloadavg()[0], "spectral": {"sizes": []}, "gpu": None}
    for size in sizes:
        spectral.plan.cache_clear()
        spectral.clear_lookups()
        _, cold, _ = timed(lambda s=size: spectral.spectral_chain(radiance, s, 8, 10.0, 1.0))
        runs, cpu, chain = [], [], None
        for _ in range(repeats):
            chain, wall, used = timed(
                lambda s=size: spectral.spectral_chain(radiance, s, 8, 10.0, 1.0)
            )
            runs.append(wall)
            cpu.append(used)
        entry = entry_for(size, runs, cpu, chain)
        entry["cold_seconds"] = cold
        report["spectral"]["sizes"].append(entry)
    if gpu:
        report["gpu"] = _gpu_chain_bench(radiance, sizes, samples, repeats, timed, entry_for)
    return report


def _gpu_chain_bench(radiance, sizes, samples, repeats, timed, entry_for) -> dict | None:
    """The GPU chain's part of :func:`run_chain_bench`; None without a GL context."""
    from envstudio.errors import ContextError
    from envstudio.gpu.context import create_headless_context, describe
    from envstudio.gpu.programs import ProgramLibrary
    from envstudio.prefilter.chain_gpu import DEFAULT_SAMPLES, gpu_prefiltered_chain

    samples = DEFAULT_SAMPLES if samples is None else samples
    start = time.perf_counter()
    try:
        ctx = create_headless_context()
    except ContextError:
        return None
    context_seconds = time.perf_counter() - start
    programs = ProgramLibrary(ctx)
    report = {
        "renderer": describe(ctx),
        "context_seconds": context_seconds,
        "samples": samples,
        "sizes": [],
    }
    try:
        for size in sizes:

            def run(s=size):
                return gpu_prefiltered_chain(ctx, programs, radiance, s, 8, 10.0, 1.0, samples)

            run()
            runs, cpu, chain = [], [], None
            for _ in range(repeats):
                chain, wall, used = timed(run)
                runs.append(wall)
                cpu.append(used)
            report["sizes"].append(entry_for(size, runs, cpu, chain))
    finally:
        programs.release()
        ctx.release()
    return report


def format_chain_report(report: dict) -> str:
    """The chain bench as text: per chain and size the time and speed-up, each level's errors."""
    lines = [f"8-level Phong cube chains (load {report['load_average']:.1f}); cmft: issue 14"]
    gpu = report.get("gpu")
    parts = [("CPU spectral (prefilter.spectral)", report["spectral"])]
    if gpu is None:
        lines.append("GPU chain: no GL context")
    else:
        parts.append(
            (
                f"GPU chain on {gpu['renderer']}, {gpu['samples']} samples at level 0 "
                f"(context {gpu['context_seconds']:.2f} s, not counted)",
                gpu,
            )
        )
    for title, part in parts:
        lines.append(title)
        for entry in part["sizes"]:
            line = (
                f"  {entry['size']}²: {entry['seconds']:.3f} s, CPU {entry['cpu_seconds']:.3f} s "
                f"(best of {len(entry['runs'])})"
            )
            if "cold_seconds" in entry:
                line += f", cold (tables built) {entry['cold_seconds']:.3f} s"
            if "cmft_seconds" in entry:
                line += f"; cmft {entry['cmft_seconds']} s: {entry['speedup_over_cmft']:.2f}x"
            lines.append(line)
            for k, level in enumerate(entry.get("levels", [])):
                lines.append(
                    f"    level {k}: {level['face']}² N = {level['exponent']:.4g}: "
                    f"rms {100 * level['rms']:.3f} %, max {100 * level['max']:.3f} % of the mean"
                )
    return "\n".join(lines)
