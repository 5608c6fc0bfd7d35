"""The atlas's outputs: ``atlas.json``, ``atlas.csv``, ``atlas.png`` and ``index.html``.

The page is one file beside the cells' images and opens with no server: a
matrix per (N, k_d) of methods × (environment, shape) coloured by error with
the image and its heat map on hover, an error-against-cost chart per N with
the Pareto front, a summary table per method, and "where it breaks": for
each method the three cells where it is worst relative to the best method of
that cell. A small script at the end marks images that did not load and
writes what it found into ``#page-check`` (the tests read it in Chromium).
"""

from __future__ import annotations

import csv
import html
import io
import math
from collections import defaultdict
from pathlib import Path

import numpy as np

from envstudio.core.images import tile
from envstudio.io.atomic import write_text_atomic
from envstudio.io.images import read_image, write_image
from envstudio.measure.atlas.entries import write_json
from envstudio.measure.atlas.grid import AtlasGrid

__all__ = ["CSV_COLUMNS", "OUTPUTS", "error_of", "pareto_front", "write_outputs"]

#: Columns of atlas.csv, one row per cell.
CSV_COLUMNS = (
    "method",
    "env",
    "mesh",
    "exponent",
    "kd",
    "camera",
    "reference_model",
    "approximation_error",
    "scene_error",
    "scene_only_error",
    "approximation_psnr_db",
    "approximation_flip",
    "psnr_db",
    "flip",
    "reliable",
    "unreliable_reason",
    "ms_per_frame",
    "cost_ratio",
    "gpu_bytes",
    "error",
    "skipped",
)
#: The files :func:`write_outputs` writes (atlas.png only when some cell has an image).
OUTPUTS = ("atlas.json", "atlas.csv", "atlas.png", "index.html")
#: Relative error at the top of the matrix's colour scale.
ERROR_SCALE = 0.3


def error_of(row: dict) -> float | None:
    """A cell's error: against the untraced reference where there is one, else the traced."""
    if row.get("error") or row.get("skipped"):
        return None
    value = row.get("approximation_error")
    return row.get("scene_error") if value is None else value


def pareto_front(points: list[tuple[float, float, str]]) -> list[tuple[float, float, str]]:
    """The (cost, error, name) points no other point beats in both, by increasing cost."""
    front, best = [], math.inf
    for cost, error, name in sorted(points):
        if error < best:
            front.append((cost, error, name))
            best = error
    return front


def write_outputs(grid: AtlasGrid, rows: list[dict], folder: Path) -> list[Path]:
    """Write atlas.json (strict JSON), atlas.csv, atlas.png (when images exist) and index.html."""
    folder = Path(folder)
    written = []
    document = {"grid": grid.to_json(), "cells": rows, "summary": summary(rows)}
    write_json(folder / "atlas.json", document, indent=1)
    written.append(folder / "atlas.json")
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, CSV_COLUMNS, extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    write_text_atomic(folder / "atlas.csv", buffer.getvalue())
    written.append(folder / "atlas.csv")
    montage = _montage(grid, rows, folder)
    if montage is not None:
        written.append(write_image(folder / "atlas.png", montage))
    write_text_atomic(folder / "index.html", _page(grid, rows))
    written.append(folder / "index.html")
    return written


def summary(rows: list[dict]) -> list[dict]:
    """Per method: median and worst approximation and scene error, the worst cell, the cost."""
    by_method = defaultdict(list)
    for row in rows:
        by_method[row["method"]].append(row)
    out = []
    for method, cells in by_method.items():
        good = [r for r in cells if error_of(r) is not None]
        worst = max(good, key=error_of, default=None)
        scene = _present(good, "scene_error")
        approx = _present(good, "approximation_error")
        out.append(
            {
                "method": method,
                "cells": len(cells),
                "failed": sum(1 for r in cells if r.get("error")),
                "skipped": sum(1 for r in cells if r.get("skipped")),
                "marked": sum(1 for r in good if not r.get("reliable", True)),
                "median_approximation_error": _median(approx),
                "worst_approximation_error": max(approx, default=None),
                "median_scene_error": _median(scene),
                "worst_scene_error": max(scene, default=None),
                "worst_cell": _cell_name(worst) if worst else None,
                "median_cost_ratio": _median([r["cost_ratio"] for r in good]),
                "median_gpu_mb": _median([r["gpu_bytes"] / 2**20 for r in good]),
            }
        )
    return out


def _present(rows: list[dict], key: str) -> list[float]:
    return [r[key] for r in rows if r.get(key) is not None]


def _median(values: list[float]) -> float | None:
    return float(np.median(values)) if values else None


def _cell_name(row: dict) -> str:
    camera = f", camera {row['camera']}" if row.get("camera") else ""
    return (
        f"{Path(row['env']).stem}, {Path(row['mesh']).stem}, N = {row['exponent']:g}, "
        f"k_d = {row['kd']:g}{camera}"
    )


def _montage(grid: AtlasGrid, rows: list[dict], folder: Path):
    """Methods × environments at the middle N, first shape, first k_d, camera 0 (for a paper)."""
    exponent = sorted(grid.exponents)[len(grid.exponents) // 2]
    chosen = {
        (r["method"], r["env"]): r
        for r in rows
        if error_of(r) is not None
        and r["exponent"] == exponent
        and r["mesh"] == grid.meshes[0]
        and r["kd"] == grid.kds[0]
        and r["camera"] == 0
    }
    w, h = grid.size
    blank = np.full((h, w, 3), 64, np.uint8)  # a cell without an image (failed, no bake)
    panels = []
    for method in grid.methods:
        line = []
        for env in grid.envs:
            row = chosen.get((method, env))
            path = folder / "cells" / row["image"] if row else None
            line.append(_to_uint8(read_image(path)) if path and path.exists() else blank)
        panels.append(line)
    return tile(panels) if chosen else None


def _to_uint8(image) -> np.ndarray:
    pixels = np.asarray(image)[..., :3]
    if pixels.dtype != np.uint8:
        pixels = np.clip(np.round(pixels * 255.0), 0, 255).astype(np.uint8)
    return pixels


# -- the page ---------------------------------------------------------------------------------


def _page(grid: AtlasGrid, rows: list[dict]) -> str:
    sections = [_summary_table(rows)]
    for n in grid.exponents:
        at_n = [r for r in rows if r["exponent"] == n]
        sections.append(f"<h2>N = {n:g}</h2>")
        sections.append(_chart(at_n, n))
        for kd in grid.kds:
            sections.append(_matrix(grid, [r for r in at_n if r["kd"] == kd], n, kd))
    sections.append(_where_it_breaks(rows))
    w, h = grid.size
    title = (
        f"envstudio atlas: {len(grid.methods)} methods, {len(grid.envs)} environments, "
        f"{len(grid.meshes)} shapes, N = {', '.join(f'{n:g}' for n in grid.exponents)}, "
        f"k_d = {', '.join(f'{k:g}' for k in grid.kds)}, {w}×{h}, {grid.cameras} camera(s)"
    )
    return _TEMPLATE.format(
        title=html.escape(title), body="\n".join(sections), scale=f"{100 * ERROR_SCALE:g}"
    )


def _colour(error: float | None) -> str:
    if error is None:
        return "#555"
    t = min(max(error / ERROR_SCALE, 0.0), 1.0)
    hue = 120.0 * (1.0 - t)  # green (0) to red (ERROR_SCALE and above)
    return f"hsl({hue:.0f}, 65%, 35%)"


def _percent(value: float | None) -> str:
    return "–" if value is None else f"{100 * value:.1f} %"


def _matrix(grid: AtlasGrid, rows: list[dict], n: float, kd: float) -> str:
    columns = [(env, mesh) for env in grid.envs for mesh in grid.meshes]
    head = "".join(
        f"<th>{html.escape(Path(env).stem)}<br>{html.escape(Path(mesh).stem)}</th>"
        for env, mesh in columns
    )
    lines = []
    for method in grid.methods:
        cells = []
        for env, mesh in columns:
            here = [r for r in rows if (r["method"], r["env"], r["mesh"]) == (method, env, mesh)]
            cells.append(_matrix_cell(here))
        lines.append(f"<tr><th>{html.escape(method)}</th>{''.join(cells)}</tr>")
    caption = (
        f"N = {n:g}, k_d = {kd:g}: approximation error (median relative, against the untraced "
        "reference; the traced one where the reference does not trace), median over cameras; "
        "† the scene error is not reliable: its reference's noise can move it by a tenth of "
        "itself or more (the reason on hover)"
    )
    return (
        f'<p class="caption">{caption}</p><table class="matrix"><tr><th></th>{head}</tr>'
        f"{''.join(lines)}</table>"
    )


def _matrix_cell(rows: list[dict]) -> str:
    if not rows:
        return '<td class="none">not measured</td>'
    failed = [r for r in rows if r.get("error")]
    if failed:
        return f'<td class="none" title="{html.escape(failed[0]["error"])}">failed</td>'
    skipped = [r for r in rows if r.get("skipped")]
    if skipped:
        reason = html.escape(skipped[0]["skipped"])
        return f'<td class="none" title="{reason}">{reason.split(":")[0]}</td>'
    errors = [error_of(r) for r in rows]
    value = _median([e for e in errors if e is not None])
    first = min(rows, key=lambda r: r["camera"])
    marked = [r for r in rows if not r.get("reliable", True)]
    tip = (
        f"{_cell_name(first)}: approximation {_percent(first.get('approximation_error'))}, "
        f"scene {_percent(first.get('scene_error'))}, cost × {first['cost_ratio']:.2f}"
    )
    if marked:
        reason = marked[0].get("unreliable_reason") or "see the cell's compare.md"
        tip += f"; † scene error unreliable: {reason}"
    tip = html.escape(tip)
    mark = " †" if marked else ""
    images = "".join(
        f'<img src="cells/{html.escape(first[k])}" alt="{k}">' for k in ("image", "heat_map")
    )
    return (
        f'<td style="background:{_colour(value)}" title="{tip}">'
        f'<a href="cells/{html.escape(first["image"])}">{_percent(value)}{mark}</a>'
        f'<span class="hover">{images}</span></td>'
    )


def _chart(rows: list[dict], n: float) -> str:
    """Median error against median cost ratio per method, log cost axis, the Pareto front."""
    points = []
    by_method = defaultdict(list)
    for r in rows:
        if error_of(r) is not None:
            by_method[r["method"]].append(r)
    for method, cells in by_method.items():
        cost = float(np.median([c["cost_ratio"] for c in cells]))
        error = float(np.median([error_of(c) for c in cells]))
        points.append((max(cost, 1e-3), error, method))
    if not points:
        return "<p>No measured cells at this N.</p>"
    width, height, pad = 520, 320, 50
    costs = [math.log10(p[0]) for p in points]
    lo, hi = min(costs) - 0.2, max(costs) + 0.2
    top = max(p[1] for p in points) * 1.15 or 1.0

    def xy(cost: float, error: float) -> tuple[float, float]:
        x = pad + (math.log10(cost) - lo) / (hi - lo) * (width - 2 * pad)
        y = height - pad - error / top * (height - 2 * pad)
        return x, y

    front = pareto_front(points)
    path = " ".join(f"{x:.1f},{y:.1f}" for x, y in (xy(c, e) for c, e, _ in front))
    marks = []
    for cost, error, name in points:
        x, y = xy(cost, error)
        marks.append(
            f'<circle cx="{x:.1f}" cy="{y:.1f}" r="5"><title>{html.escape(name)}: '
            f"{_percent(error)}, cost × {cost:.2f}</title></circle>"
            f'<text x="{x + 7:.1f}" y="{y - 7:.1f}">{html.escape(name)}</text>'
        )
    axes = (
        f'<line x1="{pad}" y1="{height - pad}" x2="{width - pad}" y2="{height - pad}"/>'
        f'<line x1="{pad}" y1="{pad}" x2="{pad}" y2="{height - pad}"/>'
        f'<text x="{width / 2:.0f}" y="{height - 12}">ms per frame ÷ mirror\'s (log)</text>'
        f'<text x="8" y="{pad - 14}">median error (top {_percent(top)})</text>'
    )
    return (
        f'<figure><svg class="chart" width="{width}" height="{height}" '
        f'viewBox="0 0 {width} {height}">{axes}'
        f'<polyline class="front" points="{path}"/>{"".join(marks)}</svg>'
        f"<figcaption>N = {n:g}: error against cost per method (median over cells); the line "
        "joins the Pareto front (no method is both cheaper and more accurate).</figcaption>"
        "</figure>"
    )


def _summary_table(rows: list[dict]) -> str:
    lines = []
    for s in summary(rows):
        gpu = "–" if s["median_gpu_mb"] is None else f"{s['median_gpu_mb']:.3g}"
        cost = "–" if s["median_cost_ratio"] is None else f"{s['median_cost_ratio']:.2f}"
        lines.append(
            f"<tr><th>{html.escape(s['method'])}</th><td>{s['cells']}</td><td>{s['failed']}</td>"
            f"<td>{s['skipped']}</td><td>{s['marked']}</td>"
            f"<td>{_percent(s['median_approximation_error'])}</td>"
            f"<td>{_percent(s['worst_approximation_error'])}</td>"
            f"<td>{_percent(s['median_scene_error'])}</td>"
            f"<td>{_percent(s['worst_scene_error'])}</td>"
            f"<td>{html.escape(s['worst_cell'] or '–')}</td><td>{cost}</td><td>{gpu}</td></tr>"
        )
    head = "".join(
        f"<th>{c}</th>"
        for c in (
            "method",
            "cells",
            "failed",
            "input missing",
            "marked †",
            "approximation error, median",
            "worst",
            "scene error, median",
            "worst",
            "worst cell",
            "cost ÷ mirror",
            "GPU MB",
        )
    )
    return f'<h2>Summary</h2><table class="summary"><tr>{head}</tr>{"".join(lines)}</table>'


def _where_it_breaks(rows: list[dict]) -> str:
    """Per method, the three cells where its error is largest relative to the cell's best."""
    best = defaultdict(lambda: math.inf)
    for r in rows:
        e = error_of(r)
        if e is not None:
            key = (r["env"], r["mesh"], r["exponent"], r["kd"], r["camera"])
            best[key] = min(best[key], e)
    parts = ["<h2>Where it breaks</h2>"]
    for method in dict.fromkeys(r["method"] for r in rows):
        ranked = []
        for r in rows:
            e = error_of(r)
            if r["method"] != method or e is None:
                continue
            floor = best[(r["env"], r["mesh"], r["exponent"], r["kd"], r["camera"])]
            ranked.append((e / max(floor, 1e-6), r))
        ranked.sort(key=lambda pair: -pair[0])
        figures = "".join(
            "<figure>"
            + "".join(
                f'<img src="cells/{html.escape(r[k])}" alt="{k}">'
                for k in ("image", "heat_map", "reference_image")
            )
            + f"<figcaption>{html.escape(_cell_name(r))}: {_percent(error_of(r))}, "
            f"{ratio:.1f} × the best method's</figcaption></figure>"
            for ratio, r in ranked[:3]
        )
        parts.append(f"<h3>{html.escape(method)}</h3><div class='row'>{figures}</div>")
    return "\n".join(parts)


_TEMPLATE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{ background: #1e1e1e; color: #ddd; font-family: sans-serif; margin: 1.5em; }}
table {{ border-collapse: collapse; margin: 1em 0; }}
th, td {{ padding: 0.3em 0.6em; border: 1px solid #333; text-align: right; }}
p.caption {{ color: #aaa; margin-bottom: 0; }}
.matrix td {{ position: relative; color: #fff; }}
.matrix a {{ color: #fff; text-decoration: none; }}
.matrix .hover {{ display: none; position: absolute; left: 100%; top: 0; z-index: 2;
  background: #000; padding: 4px; white-space: nowrap; }}
.matrix td:hover .hover {{ display: block; }}
.matrix img, figure img {{ width: 128px; image-rendering: pixelated; margin-right: 4px; }}
td.none {{ color: #888; }}
.chart line {{ stroke: #888; }}
.chart text {{ fill: #ddd; font-size: 12px; }}
.chart circle {{ fill: #4fc3f7; }}
.chart .front {{ fill: none; stroke: #ffb74d; stroke-width: 2; }}
.row {{ display: flex; flex-wrap: wrap; gap: 1em; }}
figcaption {{ font-size: 12px; color: #aaa; max-width: 420px; }}
img.missing {{ outline: 2px solid red; }}
</style>
</head>
<body>
<h1>{title}</h1>
<p>Errors are median relative luminance errors over the reflector; the colour scale runs from
0 (green) to {scale} % (red). Cost: ms per frame as a ratio to <code>mirror</code> in the same
run. GPU MB: the textures and buffers the method holds (an estimate).</p>
{body}
<p id="page-check"></p>
<script>
window.addEventListener("load", () => {{
  const images = Array.from(document.images);
  const broken = images.filter((img) => !img.complete || img.naturalWidth === 0);
  broken.forEach((img) => img.classList.add("missing"));
  const points = document.querySelectorAll("svg.chart circle").length;
  document.getElementById("page-check").textContent =
    `images ${{images.length}} broken ${{broken.length}} chart points ${{points}}`;
}});
</script>
</body>
</html>
"""
