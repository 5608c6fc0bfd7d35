"""The PEM bake's numbers (issue 18, "Numbers to reach"): quality, time per view, scaling.

Not tests (this machine is shared and noisy): a command that prints JSON::

    python -m envstudio.methods.pem.numbers [--views 3] [--size 256] [--em-size 64]
    python -m envstudio.methods.pem.numbers --scaling [--views 24] [--size 64] [--em-size 16]

- :func:`view_numbers`: for views of the default arc, each traced and inferred
  in this process (:func:`~envstudio.methods.pem.bake.bake.bake_view`, the bake's work
  unit): trace and inference seconds, and the PSNR over the reflectors'
  interior pixels of the predicted playback of each model against the traced
  composite (methods/pem/bake/models.py: layered, sphere at infinity, static EM), with
  the ceiling any prediction of that form can reach (the layers' own
  recombination against the composite: with several samples per pixel, F, d and
  I vary inside a pixel).
- :func:`scaling`: the same bake on a Dask LocalCluster of K = 1 and 2 worker
  processes; the issue's target is wall(K) ≤ 1.5 · wall(1) / K. ``view_s`` is the
  sum over views of their trace and inference seconds as the workers measured
  them: when it grows with K, the workers are competing for cores.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from envstudio.io.scene_file import load_scene, resolve_scene
from envstudio.methods.pem.bake.bake import ViewTask, _context, bake_view
from envstudio.methods.pem.bake.infer import psnr
from envstudio.methods.pem.bake.lookups import LOD_BIAS, PLAYBACK, pixel_lookups
from envstudio.methods.pem.bake.models import fit_pixels
from envstudio.methods.pem.bake.views import arc_views
from envstudio.methods.pem.commands import run_bake
from envstudio.methods.pem.lookups_gl import GlLookups

__all__ = ["main", "scaling", "view_numbers"]


def view_numbers(
    scene: str = "room",
    views: int = 3,
    step: float = 1.0,
    size: int = 256,
    samples: int = 4,
    em_size: int = 64,
    smoothness: float = 1e-3,
    lod_bias: float = LOD_BIAS,
) -> list[dict]:
    """Per view: seconds, predicted playback PSNRs and their ceiling (module docstring)."""
    path = str(resolve_scene(scene).resolve())
    scene_obj = load_scene(path)
    out = []
    for i, c in enumerate(arc_views(scene_obj.camera, views, step).cameras()):
        task = ViewTask(
            path, i, float(c.azimuth), float(c.elevation), float(c.distance),
            tuple(float(t) for t in c.target), float(c.fov_y), size, samples, em_size,
            smoothness, 0, smoothness, lod_bias, gl_lookups=GlLookups,
        )  # fmt: skip
        result = bake_view(task)
        ctx = _context(path)
        view = ctx["tracer"].trace(task.camera(), size, samples, i)
        lookups = pixel_lookups(
            ctx["tracer"], task.camera(), size, em_size, ctx["box"], ctx["ellipsoids"],
            ctx["origins"],
        )  # fmt: skip
        mask = np.zeros((size, size), bool)
        for p in range(len(view.part_names)):
            mask |= fit_pixels(view, lookups, p)
        out.append(
            {
                "view": i,
                "azimuth": float(c.azimuth),
                "trace_s": round(float(result["trace_seconds"]), 3),
                "infer_s": round(float(result["infer_seconds"]), 3),
                "pixels": int(mask.sum()),
                **{f"psnr_{n}": round(float(result[f"playback_{n}"]), 2) for n in PLAYBACK},
                "psnr_ceiling": round(psnr(view.recombine()[mask], view.composite[mask]), 2),
            }
        )
    return out


def scaling(
    scene: str = "room",
    views: int = 24,
    size: int = 64,
    samples: int = 4,
    em_size: int = 16,
    workers: tuple[int, ...] = (1, 2),
) -> list[dict]:
    """Wall time of one bake on a LocalCluster of each K in ``workers`` (module docstring)."""
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in workers:
            target = Path(tmp) / f"k{k}.pem"
            start = time.perf_counter()
            report = run_bake(
                scene,
                lambda camera: arc_views(camera, views, 1.0),
                target,
                size=size,
                samples=samples,
                em_size=em_size,
                scheduler="local",
                dask_workers=k,
            )
            out.append(
                {
                    "workers": k,
                    "wall_s": round(time.perf_counter() - start, 2),
                    "view_s": round(sum(report.trace_seconds) + sum(report.infer_seconds), 2),
                }
            )
    base = out[0]["wall_s"] * out[0]["workers"]
    for row in out:
        row["target_s"] = round(1.5 * base / row["workers"], 2)
        row["within_target"] = row["wall_s"] <= row["target_s"]
    return out


def main(argv: list[str] | None = None) -> int:
    """Print :func:`view_numbers` (or :func:`scaling` with ``--scaling``) as JSON."""
    parser = argparse.ArgumentParser(prog="python -m envstudio.methods.pem.numbers")
    parser.add_argument("--scene", default="room")
    parser.add_argument("--views", type=int)
    parser.add_argument("--size", type=int)
    parser.add_argument("--samples", type=int, default=4)
    parser.add_argument("--em-size", type=int)
    parser.add_argument("--scaling", action="store_true", help="LocalCluster K = 1 and 2")
    args = parser.parse_args(argv)
    if args.scaling:
        rows = scaling(
            args.scene, args.views or 24, args.size or 64, args.samples, args.em_size or 16
        )
    else:
        rows = view_numbers(
            args.scene, args.views or 3, 1.0, args.size or 256, args.samples, args.em_size or 64
        )
    print(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
