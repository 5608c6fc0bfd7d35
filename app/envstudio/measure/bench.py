"""``envstudio bench``: per-method frame and pass times after a warm-up.

Every registered method is benchmarked with no extra code. Times are the
median and 95th percentile over ``frames`` frames in milliseconds, with the
clock named (GPU timer queries on real GPUs; wall time around ``finish()`` on
software renderers, whose timer queries under-report).
"""

from __future__ import annotations

import sys
import time

import numpy as np
from tqdm import tqdm

from envstudio.engine.registry import available_methods
from envstudio.engine.session import RenderSession
from envstudio.gpu.context import describe


def _summary(samples: list[float]) -> dict[str, float]:
    values = np.asarray(samples, dtype=np.float64)
    return {"median_ms": float(np.median(values)), "p95_ms": float(np.percentile(values, 95))}


def run_bench(
    session: RenderSession,
    methods: list[str],
    size: tuple[int, int],
    frames: int,
    warmup: int = 5,
    progress: bool = True,
) -> dict:
    """Benchmark ``methods`` in one session.

    Returns
    -------
    dict
        JSON-ready: device, clock, size, triangles, and per method its
        parameters, ``frame`` (median/p95 of the whole frame, wall-clock with
        a finish at both ends) and ``passes`` (median/p95 of each pass).
    """
    triangles = sum(n.mesh.triangle_count for n in session.gpu_scene.reflectors())
    report = {
        "device": describe(session.ctx),
        "clock": session.renderer.timer.clock,
        "size": list(size),
        "frames": frames,
        "warmup": warmup,
        "reflector_triangles": triangles,
        "methods": {},
    }
    bar = tqdm(
        total=len(methods) * (frames + warmup),
        desc="bench",
        unit="frame",
        disable=not progress,
        file=sys.stderr,
    )
    for name in methods:
        method = session.method(name)
        frame_ms: list[float] = []
        passes: dict[str, list[float]] = {}
        for i in range(warmup + frames):
            session.ctx.finish()
            start = time.perf_counter()
            stats = session.render_offscreen(method, size)
            session.ctx.finish()
            elapsed = (time.perf_counter() - start) * 1e3
            bar.update(1)
            if i < warmup:
                continue
            frame_ms.append(elapsed)
            for pass_name, ms in stats.passes_ms.items():
                passes.setdefault(pass_name, []).append(ms)
        report["methods"][name] = {
            "parameters": method.values.as_dict(),
            "frame": _summary(frame_ms),
            "passes": {k: _summary(v) for k, v in passes.items()},
        }
        notes = method.bench_notes()
        if notes:
            report["methods"][name]["notes"] = notes
    bar.close()
    baseline = next(iter(available_methods()))  # the first in the switch: mirror
    if baseline in report["methods"]:
        reference_ms = report["methods"][baseline]["frame"]["median_ms"]
        for entry in report["methods"].values():
            entry["frame"][f"ratio_to_{baseline}"] = entry["frame"]["median_ms"] / reference_ms
    return report


def format_report(report: dict) -> str:
    """A plain-text table of a bench report."""
    lines = [
        f"device: {report['device']}  clock: {report['clock']}  "
        f"size: {report['size'][0]}x{report['size'][1]}  "
        f"reflector triangles: {report['reflector_triangles']}",
        f"{'method':<12} {'frame med':>10} {'frame p95':>10}  passes (median ms)",
    ]
    for name, entry in report["methods"].items():
        passes = "  ".join(f"{k}={v['median_ms']:.3f}" for k, v in entry["passes"].items())
        ratio = next(
            (
                f"  ({v:.2f}x {k[len('ratio_to_') :]})"
                for k, v in entry["frame"].items()
                if k.startswith("ratio_to_")
            ),
            "",
        )
        lines.append(
            f"{name:<12} {entry['frame']['median_ms']:>10.3f} "
            f"{entry['frame']['p95_ms']:>10.3f}  {passes}{ratio}"
        )
        for key, value in entry.get("notes", {}).items():
            lines.append(f"{'':<12} {key}: {value}")
    return "\n".join(lines)
