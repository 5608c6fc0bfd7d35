"""An atlas measured again against the record: how far each cell moved.

    python studies/atlas-full/against_before.py studies/atlas-full/atlas-spread-rule.csv \
        studies/atlas-full/atlas-bootstrap-rule.csv

Both are atlas.csv files of the same grid. For the cells measured in both: the largest change
of the approximation column (the exact references: none expected), and per mesh the median and
largest change of the scene column as a share of the earlier value, the reliable cells of
each, and the cells that moved most.
"""

from __future__ import annotations

import csv
import sys

import numpy as np

KEY = ("env", "mesh", "exponent", "method")


def read(path: str) -> dict[tuple, dict]:
    with open(path, newline="") as f:
        return {tuple(row[k] for k in KEY): row for row in csv.DictReader(f)}


def main(before_path: str, after_path: str) -> None:
    before, after = read(before_path), read(after_path)
    both = [
        k for k in after if k in before and after[k]["scene_error"] and before[k]["scene_error"]
    ]
    approximation = max(
        abs(float(after[k]["approximation_error"]) - float(before[k]["approximation_error"]))
        for k in both
    )
    print(f"{len(both)} cells in both; approximation column moved by at most {approximation:.3g}")
    for mesh in sorted({k[1] for k in both}):
        cells = [k for k in both if k[1] == mesh]
        moved = {
            k: abs(float(after[k]["scene_error"]) / float(before[k]["scene_error"]) - 1.0)
            for k in cells
        }
        shares = np.array(list(moved.values()))
        reliable = [sum(t[k]["reliable"] == "True" for k in cells) for t in (before, after)]
        median, largest = 100 * np.median(shares), 100 * shares.max()
        print(
            f"{mesh}: {len(cells)} cells; scene column moved by a median {median:.2f} % of "
            f"itself, at most {largest:.2f} %; reliable {reliable[0]} -> {reliable[1]}"
        )
        for k in sorted(moved, key=moved.get, reverse=True)[:5]:
            was, now = before[k], after[k]
            print(
                f"  {100 * moved[k]:.2f} %: {', '.join(k)}: {float(was['scene_error']):.4f} -> "
                f"{float(now['scene_error']):.4f} (reliable {was['reliable']} -> {now['reliable']})"
            )


if __name__ == "__main__":
    main(*sys.argv[1:3])
