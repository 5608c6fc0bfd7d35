"""The PEM bake's numbers (issue 18, "Numbers to reach"): quality, time per view, scaling.

Not tests (this machine is shared and noisy): a command that prints JSON::

    python studies/pem-paper-scale/numbers.py [--views 3] [--size 256] [--em-size 64]
    python studies/pem-paper-scale/numbers.py --scaling [--views 24] [--size 64] [--em-size 16]
    python studies/pem-paper-scale/numbers.py --wobble FILE.pem [--above 10]
    python studies/pem-paper-scale/numbers.py --coupling 0,0.1,1 [--tie 1e-3] [--size 128] ...
    python studies/pem-paper-scale/numbers.py --footprint-sweep 1:0,2:0,1:2,2:2

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
- :func:`wobble_numbers`: seed 003 §6's wobble of a bake (methods/pem/offmanifold.py
  ``wobble``: mean |Δ| per frame of the displayed reflector along a 0.25° sweep),
  per EM model (the PTM's too where the bake has it) and for the ray trace, and its
  largest |Δ| per frame (the PTM's "pops" where the sweep crosses a sample view).
- :func:`coupling_sweep` (issue 31, coupled inference, not in seed 003): for each
  weight γ, a small bake of the shipped arc (6 views, 2° apart), its on-manifold
  predicted playback PSNR, its wobble, and the speckle of its coarse levels
  (:func:`speckle`).
- :func:`footprint_sweep` (issue 31, not in seed 003): bakes of the shipped arc
  with coarser footprints and refits through the over, played at their sample
  views smaller than baked, where the coarse levels show.
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

__all__ = [
    "coupling_sweep",
    "footprint_sweep",
    "main",
    "scaling",
    "speckle",
    "view_numbers",
    "wobble_numbers",
]


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


def wobble_numbers(
    path: str | Path, above: float = 0.0, size: int = 128, scene: str | None = None
) -> dict[str, float]:
    """The wobble of the bake at ``path`` in ``scene`` (default the bake's), and its pops.

    Per model and ``trace``, the mean (:func:`~envstudio.methods.pem.offmanifold.wobble`)
    and, as ``"<model> max"``, the largest frame-to-frame change of the sweep
    (:func:`~envstudio.methods.pem.offmanifold.wobble_sweep`): seed 003 §6's pops of the PTM.
    """
    from envstudio.engine.session import RenderSession
    from envstudio.methods.pem import offmanifold
    from envstudio.methods.pem.bake.pem_file import load_pem

    bake = load_pem(path)
    session = RenderSession(load_scene(scene or bake.scene), cube_size=128)
    try:
        method = session.method("pem")
        method.values["pem"] = str(path)
        method.prepare(session.gpu_scene)
        changes = offmanifold.wobble_sweep(session, method, size=size, elevation_above=above)
    finally:
        session.release()
    out = {name: round(float(np.mean(c)), 5) for name, c in changes.items()}
    out.update({f"{name} max": round(float(np.max(c)), 5) for name, c in changes.items()})
    return out


def speckle(levels: list[np.ndarray], first: int = 1) -> list[float]:
    """Speckle of a MIP chain's levels k ≥ ``first`` with edge ≥ 4 (seed 003 Figure 5).

    Per level, the mean over texels of |x − the 3 × 3 mean of x on its face| (edges
    clamped), divided by the mean |x|: 0 for a constant face, large for isolated
    texels that differ from their neighbours.

    Parameters
    ----------
    levels
        L arrays (V, P, 6, n_k, n_k, C).
    """
    out = []
    for level in levels[first:]:
        a = np.asarray(level, np.float64)
        if a.shape[3] < 4:
            break
        pad = np.pad(a, [(0, 0)] * 3 + [(1, 1), (1, 1), (0, 0)], mode="edge")
        n = a.shape[3]
        blur = sum(pad[..., i : i + n, j : j + n, :] for i in range(3) for j in range(3)) / 9.0
        out.append(round(float(np.abs(a - blur).mean() / max(np.abs(a).mean(), 1e-12)), 4))
    return out


def coupling_sweep(
    weights: tuple[float, ...],
    size: int = 128,
    em_size: int = 32,
    views: int = 6,
    step: float = 2.0,
    tie: float = 1e-3,
    passes: int = 2,
    footprints: int = 1,
    over_passes: int = 0,
) -> list[dict]:
    """Per coupling weight γ: on-manifold PSNR, wobble and coarse-level speckle (module docstring).

    Each bake is the shipped arc (``views`` views ``step``° apart from the scene camera)
    at a small size, without the PTM; the wobble sweep is played at the bake's size.
    The decimated row is the speckle of the box-decimated finest level of the γ = 0 bake
    (what a filtered chain would show). ``footprints`` and ``over_passes`` are the bake's
    (run_bake; not in seed 003).
    """
    from envstudio.methods.pem.bake.mip import decimated_chain

    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for weight in weights:
            path = Path(tmp) / f"g{weight:g}.pem"
            start = time.perf_counter()
            report = run_bake(
                "room", lambda c: arc_views(c, views, step), path, size=size, em_size=em_size,
                tie=tie, ptm=False, coupling=weight, coupling_passes=passes,
                footprints=footprints, over_passes=over_passes,
            )  # fmt: skip
            seconds = time.perf_counter() - start
            bake = report.bake
            motion = wobble_numbers(path, size=size)
            row = {
                "coupling": weight,
                "tie": tie,
                "footprints": footprints,
                "over_passes": over_passes,
                "bake_s": round(seconds, 1),
                **{f"psnr_{n}": round(float(np.mean(bake.playback_psnr[n])), 2)
                   for n in ("layered", "sphere")},
                **{f"wobble_{n}": motion[n] for n in ("layered", "sphere", "static", "trace")},
                "speckle_distant": speckle(bake.maps["distant"]),
                "speckle_local_alpha": speckle([lv[..., 3:] for lv in bake.maps["local"]]),
            }  # fmt: skip
            if weight == weights[0]:
                faces_first = np.moveaxis(bake.maps["distant"][0], (0, 1), (-3, -2))
                chain = decimated_chain(faces_first)  # (6, n_k, n_k, V, P, C) per level
                row["speckle_distant_decimated"] = speckle(
                    [np.moveaxis(c, (-3, -2), (0, 1)) for c in chain]
                )
            out.append(row)
            print(json.dumps(row), flush=True)
    return out


def footprint_sweep(
    variants: tuple[tuple[int, int], ...] = ((1, 0), (2, 0), (1, 2), (2, 2)),
    played: tuple[int, ...] = (64, 128),
    size: int = 128,
    em_size: int = 32,
) -> list[dict]:
    """Playback at the sample views at smaller sizes than the bake's, per bake variant.

    For each (footprints F, refit passes K) (bake/models.py and bake/over.py, not in
    seed 003) a bake of the shipped arc (6 views 2° apart, R = ``size``, without the
    PTM) is played at every sample view at each size of ``played`` and held against a
    16-ray trace there (methods/pem/offmanifold.py ``measure``, displayed PSNR over the
    fully covered reflector pixels): where a playback smaller than the bake reads
    coarse levels, seed 003 Figure 5's speckle shows. Mean over the views.
    """
    from envstudio.engine.session import RenderSession
    from envstudio.methods.pem import offmanifold

    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for footprints, passes in variants:
            path = Path(tmp) / f"f{footprints}k{passes}.pem"
            start = time.perf_counter()
            report = run_bake(
                "room", lambda c: arc_views(c, 6, 2.0), path, size=size, em_size=em_size,
                ptm=False, footprints=footprints, over_passes=passes,
            )  # fmt: skip
            row = {"footprints": footprints, "over_passes": passes}
            row["bake_s"] = round(time.perf_counter() - start, 1)
            session = RenderSession(load_scene("room"), cube_size=128)
            try:
                method = session.method("pem")
                method.values.update({"pem": str(path), "coverage": "file"})
                method.prepare(session.gpu_scene)
                space = report.bake.view_space
                views = [
                    offmanifold.OffManifoldView(f"sample {a:g}", float(a), float(e))
                    for a in space["azimuths"]
                    for e in space["elevations"]
                ]
                for played_size in played:
                    results = offmanifold.measure(session, method, views, size=played_size)
                    for model in ("layered", "sphere", "static"):
                        row[f"{model}_{played_size}"] = round(
                            float(np.mean([r.metrics[model]["psnr"] for r in results])), 2
                        )
            finally:
                session.release()
            out.append(row)
            print(json.dumps(row), flush=True)
    return out


def main(argv: list[str] | None = None) -> int:
    """Print :func:`view_numbers` (or :func:`scaling` with ``--scaling``) as JSON."""
    parser = argparse.ArgumentParser(prog="python studies/pem-paper-scale/numbers.py")
    parser.add_argument(
        "--scene", help="shipped scene or TOML file (default room; --wobble: the bake's)"
    )
    parser.add_argument("--views", type=int)
    parser.add_argument("--size", type=int)
    parser.add_argument("--samples", type=int, default=4)
    parser.add_argument("--em-size", type=int)
    parser.add_argument("--scaling", action="store_true", help="LocalCluster K = 1 and 2")
    parser.add_argument("--wobble", metavar="FILE", help="the wobble of a .pem bake")
    parser.add_argument("--above", type=float, default=0.0, help="wobble: degrees above the arc")
    parser.add_argument("--coupling", metavar="G,G,...", help="coupling weights to sweep")
    parser.add_argument("--tie", type=float, default=1e-3, help="coupling sweep: μ")
    parser.add_argument("--passes", type=int, default=2, help="coupling sweep: coupled passes")
    parser.add_argument("--footprints", type=int, default=1, help="coupling sweep: footprints")
    parser.add_argument(
        "--footprint-sweep",
        metavar="F:K,...",
        help="bakes with F footprints and K refit passes, played smaller than baked",
    )
    parser.add_argument("--over-passes", type=int, default=0, help="coupling sweep: refits")
    args = parser.parse_args(argv)
    if args.wobble:
        rows = wobble_numbers(args.wobble, args.above, args.size or 128, args.scene)
    elif args.footprint_sweep:
        variants = tuple(
            (int(f), int(k)) for f, k in (v.split(":") for v in args.footprint_sweep.split(","))
        )
        rows = footprint_sweep(variants, size=args.size or 128, em_size=args.em_size or 32)
    elif args.coupling:
        weights = tuple(float(w) for w in args.coupling.split(","))
        rows = coupling_sweep(
            weights, args.size or 128, args.em_size or 32, args.views or 6, 2.0, args.tie,
            args.passes, args.footprints, args.over_passes,
        )  # fmt: skip
    elif args.scaling:
        rows = scaling(
            args.scene or "room",
            args.views or 24,
            args.size or 64,
            args.samples,
            args.em_size or 16,
        )
    else:
        rows = view_numbers(
            args.scene or "room",
            args.views or 3,
            1.0,
            args.size or 256,
            args.samples,
            args.em_size or 64,
        )
    print(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
