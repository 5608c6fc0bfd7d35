"""The tables of README.md from an atlas folder's atlas.json.

    python studies/atlas-full/tables.py DIR [CHARTS]

prints, in Markdown: per method its cells, reliable and marked counts and its errors (the
page's summary); per method and N the median approximation error over the scenes; and every
marked cell with its reason. With CHARTS, the page's error-against-cost charts are written
there as standalone SVG files (chart_N10.svg, ...), styled for a light background.
"""

from __future__ import annotations

import json
import re
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np


def percent(value: float | None) -> str:
    return "–" if value is None else f"{100 * value:.2f} %"


def main(folder: Path) -> None:
    document = json.loads((folder / "atlas.json").read_text())
    cells = document["cells"]
    measured = [c for c in cells if not c.get("skipped") and not c.get("error")]
    print(
        "| method | model | cells | reliable | marked † | input missing | approximation, median "
        "| worst | scene, median | worst | worst cell | cost ÷ mirror |"
    )
    print("| --- | --- | --: | --: | --: | --: | --: | --: | --: | --: | --- | --: |")
    models = {c["method"]: c.get("reference_model") or "–" for c in measured}
    for s in document["summary"]:
        mine = [c for c in measured if c["method"] == s["method"]]
        reliable = sum(1 for c in mine if c.get("reliable"))
        cost = "–" if s["median_cost_ratio"] is None else f"{s['median_cost_ratio']:.2f}"
        print(
            f"| {s['method']} | {models.get(s['method'], '–')} | {s['cells']} | {reliable} | "
            f"{len(mine) - reliable} | {s['skipped']} | "
            f"{percent(s['median_approximation_error'])} | "
            f"{percent(s['worst_approximation_error'])} | {percent(s['median_scene_error'])} | "
            f"{percent(s['worst_scene_error'])} | {s['worst_cell'] or '–'} | {cost} |"
        )
    exponents = sorted({c["exponent"] for c in measured})
    by = defaultdict(list)
    for c in measured:
        if c.get("approximation_error") is not None:
            by[c["method"], c["exponent"]].append(c["approximation_error"])
    print()
    print("| method | " + " | ".join(f"N = {n:g}" for n in exponents) + " |")
    print("| --- |" + " --: |" * len(exponents))
    for method in dict.fromkeys(c["method"] for c in measured):
        values = [by.get((method, n)) for n in exponents]
        row = " | ".join(percent(float(np.median(v))) if v else "–" for v in values)
        print(f"| {method} | {row} |")
    print()
    print("Marked cells:")
    print()
    marked = defaultdict(list)
    for c in measured:
        if not c.get("reliable"):
            reason = c.get("unreliable_reason") or own_reason(folder, c)
            scene = f"{c['env']}, {c['mesh']}, N = {c['exponent']:g}, {c['reference_model']}"
            marked[scene, reason].append(c["method"])
    for (scene, reason), methods in marked.items():
        print(f"- {scene} ({', '.join(methods)}): {reason}")


def own_reason(folder: Path, cell: dict) -> str:
    """A cell measured before the atlas kept each row's reason: its reference's clause of
    the scene's compare.json."""
    report = folder / "cells" / Path(cell["image"]).parent / "compare.json"
    prefix = f"reference ({cell['reference_model']}): "
    clauses = json.loads(report.read_text())["unreliable_reason"].split("; ")
    return next((c[len(prefix) :] for c in clauses if c.startswith(prefix)), "see compare.md")


#: The page's chart style, for a light background.
CHART_STYLE = (
    "<style>line{stroke:#888}text{fill:#222;font-size:12px;font-family:sans-serif}"
    "circle{fill:#1976d2}.front{fill:none;stroke:#f57c00;stroke-width:2}</style>"
)


def write_charts(folder: Path, out: Path) -> None:
    """The page's charts, one per N in the grid's order, as standalone SVG files."""
    page = (folder / "index.html").read_text()
    exponents = json.loads((folder / "atlas.json").read_text())["grid"]["exponents"]
    charts = re.findall(r"<svg class=\"chart\".*?</svg>", page, flags=re.S)
    for n, chart in zip(exponents, charts, strict=True):
        svg = chart.replace("<svg ", '<svg xmlns="http://www.w3.org/2000/svg" ', 1)
        svg = svg.replace(">", ">" + CHART_STYLE, 1)
        (out / f"chart_N{n:g}.svg").write_text(svg)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
    if len(sys.argv) > 2:
        write_charts(Path(sys.argv[1]), Path(sys.argv[2]))
