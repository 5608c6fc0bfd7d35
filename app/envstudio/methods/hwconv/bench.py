"""``envstudio bench --methods hwconv --hwconv-table``: seed 004 §5.2's timing table.

For each Phong exponent, the filter sizes and shrink factors radii.plan_filters
computes for the paper's map (512 texels across a face's disc, 64 of border, ε = 0.1,
maximum kernel 7) beside the paper's, and the time per frame of refilter + render
with two passes and with one, each as a ratio to the static-map render (the same
method, nothing refiltered) in the same run, as DESIGN.md asks of timings on a
shared machine. The paper's fps are those of an SGI O2 and are listed as printed.

The timed map must hold the largest kernel's reach in its border
(radii.FilterPlan.check_border): at 512 texels N = 10 needs 130 texels and N = 50
needs 68, more than the paper's 64, so the timings use the border the smallest
exponent needs (the filter sizes and shrink factors do not depend on the border).
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np
from tqdm import tqdm

from envstudio.gpu.context import describe
from envstudio.methods.hwconv.radii import plan_filters
from envstudio.plugin import Session

__all__ = ["PAPER_TABLE", "format_table", "paper_rows", "run_table"]

#: §5.2's table, SGI O2, 512 × 1024 map, border 64, ε = 0.1, maximum kernel 7:
#: exponent → (size small, size large, shrink small, shrink large, fps 2-pass, fps 1-pass).
PAPER_TABLE = {
    10: (174, 260, 32, 64, 25, 33),
    50: (78, 136, 16, 32, 20, 33),
    100: (56, 100, 8, 16, 16, 25),
    250: (36, 66, 8, 16, 16, 25),
    500: (26, 48, 4, 8, 9, 11),
}
_PAPER_MAP = {"size": 512, "border": 64, "epsilon": 0.1, "max_kernel": 7}


def paper_rows(
    exponents: list[float],
    size: int = 512,
    border: int = 64,
    epsilon: float = 0.1,
    max_kernel: int = 7,
) -> list[dict]:
    """Filter sizes and shrink factors for each exponent, with the paper's where it has them.

    Returns
    -------
    list of dict
        Per exponent: ``radius``, ``size`` and ``shrink`` as [small, large] (texels of
        the full-size map), ``border_needed`` (⌈r_l⌉) and ``paper`` (the row of
        :data:`PAPER_TABLE` or None).
    """
    rows = []
    for exponent in exponents:
        plan = plan_filters(exponent, epsilon, size, border, max_kernel)
        paper = PAPER_TABLE.get(int(exponent)) if float(exponent).is_integer() else None
        rows.append(
            {
                "exponent": float(exponent),
                "radius": [plan.radius_small, plan.radius_large],
                "size": [plan.size_small, plan.size_large],
                "shrink": [plan.shrink_small, plan.shrink_large],
                "border_needed": math.ceil(plan.radius_large - 1e-9),
                "paper": None
                if paper is None
                else {"size": list(paper[:2]), "shrink": list(paper[2:4]), "fps": list(paper[4:])},
            }
        )
    return rows


def _time_frames(session: Session, method, size, frames: int, warmup: int, bar) -> float:
    """Median wall-clock ms per frame, with a finish on both sides of each."""
    samples = []
    for i in range(warmup + frames):
        session.ctx.finish()
        start = time.perf_counter()
        session.render_offscreen(method, size)
        session.ctx.finish()
        bar.update(1)
        if i >= warmup:
            samples.append((time.perf_counter() - start) * 1e3)
    return float(np.median(samples))


def run_table(
    session: Session,
    exponents: list[float],
    size: tuple[int, int],
    frames: int,
    warmup: int,
    progress: bool = True,
) -> dict:
    """Compute the table and time static, 2-pass and 1-pass frames for every exponent.

    The session's ``hwconv`` method keeps the map parameters it was given (``map_size``,
    ``epsilon``, ``max_kernel``, the display); its border is raised to what the
    smallest exponent needs when it is narrower.

    Returns
    -------
    dict
        JSON-ready: device, clock, frame size, the map timed, and per exponent the
        row of :func:`paper_rows` plus ``ms`` (static, two_pass, one_pass) and
        ``ratio`` (two_pass, one_pass over static).
    """
    method = session.method("hwconv")
    values = method.values
    map_size, epsilon = int(values["map_size"]), float(values["epsilon"])
    max_kernel = int(values["max_kernel"])
    timed_rows = paper_rows(exponents, map_size, int(values["border"]), epsilon, max_kernel)
    values["border"] = max(int(values["border"]), *(r["border_needed"] for r in timed_rows))
    values["view"] = "reflector"
    rows = paper_rows(exponents, **_PAPER_MAP)
    bar = tqdm(
        total=3 * len(exponents) * (frames + warmup),
        desc="hwconv table",
        unit="frame",
        disable=not progress,
        file=sys.stderr,
    )
    for row, timed in zip(rows, timed_rows, strict=True):
        values["phong_exponent"] = row["exponent"]
        ms = {}
        for name, refilter, one_pass in (
            ("static", False, False),
            ("two_pass", True, False),
            ("one_pass", True, True),
        ):
            values.update({"refilter_every_frame": refilter, "one_pass": one_pass})
            ms[name] = _time_frames(session, method, size, frames, warmup, bar)
        row["timed_map"] = {"size": timed["size"], "shrink": timed["shrink"]}
        row["ms"] = ms
        row["ratio"] = {k: ms[k] / ms["static"] for k in ("two_pass", "one_pass")}
    bar.close()
    return {
        "device": describe(session.ctx),
        "clock": "wall+finish",
        "frame_size": list(size),
        "map": {
            "size": map_size,
            "border": int(values["border"]),
            "epsilon": epsilon,
            "max_kernel": max_kernel,
        },
        "paper_map": dict(_PAPER_MAP),
        "reflector_triangles": sum(n.mesh.triangle_count for n in session.gpu_scene.reflectors()),
        "frames": frames,
        "rows": rows,
    }


def format_table(report: dict) -> str:
    """The table as Markdown: ours beside the paper's, then the timings."""
    m, p = report["map"], report["paper_map"]
    lines = [
        f"filter sizes and shrink factors: {p['size']}-texel disc, ε = {p['epsilon']:g}, "
        f"maximum kernel {p['max_kernel']} (ours | paper)",
        "",
        "| N | size small | size large | shrink small | shrink large | border needed |",
        "| ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for row in report["rows"]:
        paper = row["paper"] or {"size": ["–", "–"], "shrink": ["–", "–"]}
        cells = [f"{row['exponent']:g}"]
        for key in ("size", "shrink"):
            cells += [f"{row[key][i]} \\| {paper[key][i]}" for i in range(2)]
        cells.append(str(row["border_needed"]))
        lines.append("| " + " | ".join(cells) + " |")
    lines += [
        "",
        f"refilter + render per frame, {report['device']}, {report['clock']}, frame "
        f"{report['frame_size'][0]}x{report['frame_size'][1]}, "
        f"{report['reflector_triangles']} reflector triangles, map {m['size']} + 2·{m['border']}, "
        f"median of {report['frames']}",
        "",
        "| N | static ms | 2-pass ms | 1-pass ms | 2-pass / static | 1-pass / static "
        "| paper fps 2-pass | paper fps 1-pass |",
        "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for row in report["rows"]:
        ms, ratio = row["ms"], row["ratio"]
        fps = row["paper"]["fps"] if row["paper"] else ["–", "–"]
        lines.append(
            f"| {row['exponent']:g} | {ms['static']:.2f} | {ms['two_pass']:.2f} | "
            f"{ms['one_pass']:.2f} | {ratio['two_pass']:.2f} | {ratio['one_pass']:.2f} | "
            f"{fps[0]} | {fps[1]} |"
        )
    return "\n".join(lines)
