"""The full-orbit PEM's numbers (issue 31 part 1): its spacing, and its quality anywhere.

Not tests (measurements on a shared machine; studies/pem-orbit/README.md has the results)::

    python studies/pem-orbit/orbit_numbers.py --spacing 40,20,10,5 [--cameras 4]
    python studies/pem-orbit/orbit_numbers.py --orbit [--cameras 24] [--em-size 64] \
        [--fit refit|seed003] [--first K] [--coupling 0.1]
    python studies/pem-orbit/orbit_numbers.py --wobble 22,18 [--size 128]

- :func:`spacing_sweep`: at random cameras (elevations 15°–60°, so that the
  coarsest grid's views stay above the floor), for each spacing s a 2 × 2 grid bake
  whose cell has the camera at its centre (midway between samples on both axes),
  played back there and held against the bake's ray trace at that camera
  (methods/pem/offmanifold.py ``measure``). The issue's rule: the coarsest s whose
  playback is within 1 dB of the 2× denser grid's (s / 2, the same camera at its
  cell's centre).
- :func:`orbit_quality`: at random cameras over the whole orbit, the layered
  PEM, the sphere at infinity, the static EM and the PTM of the full orbit
  (methods/pem/bake/orbit.py), each against the ray trace at that camera: PSNR and
  FLIP per camera, and their minimum, median and maximum.
- :func:`orbit_wobble`: seed 003 §6's wobble and pops of the full orbit along a slow
  azimuth sweep that crosses a sample view.

Random cameras are uniform over the sphere of directions about the target between
:data:`LOWEST` and 89° elevation (below, the room's camera is under its floor), at
the scene camera's distance.
"""

from __future__ import annotations

import argparse
import itertools
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from envstudio.engine.session import RenderSession
from envstudio.io.scene_file import load_scene
from envstudio.methods.pem import offmanifold
from envstudio.methods.pem.bake.bake import run_bake
from envstudio.methods.pem.bake.orbit import ORBIT_BAKE, ORBIT_COUPLING
from envstudio.methods.pem.bake.views import ELEVATION_LIMIT, grid_views
from envstudio.methods.pem.blending import ptm_blend, view_blend
from envstudio.methods.pem.lookups_gl import GlLookups
from envstudio.scene.camera import OrbitCamera

__all__ = [
    "LOWEST",
    "main",
    "orbit_quality",
    "orbit_wobble",
    "random_cameras",
    "spacing_sweep",
]

#: The lowest elevation measured, degrees: below about −9.6° the room's camera (3 units
#: from the teapot, whose floor is 0.5 below it) is under the floor and sees no reflector.
LOWEST = -9.0


def random_cameras(
    count: int, seed: int = 31, lowest: float = LOWEST, highest: float = ELEVATION_LIMIT
) -> list[tuple[float, float]]:
    """``count`` (azimuth, elevation) pairs in degrees, uniform over the sphere's band
    ``lowest`` ≤ elevation ≤ ``highest``."""
    rng = np.random.default_rng(seed)
    azimuth = rng.uniform(0.0, 360.0, count)
    band = np.sin(np.radians([lowest, highest]))
    elevation = np.degrees(np.arcsin(rng.uniform(band[0], band[1], count)))
    return [(float(a), float(e)) for a, e in zip(azimuth, elevation, strict=True)]


def _measure(session, method, cameras, size: int) -> list[dict]:
    views = [offmanifold.OffManifoldView(f"{a:.1f}/{e:.1f}", a, e) for a, e in cameras]
    results = offmanifold.measure(session, method, views, size=size)
    return [
        {
            "azimuth": round(r.view.azimuth, 2),
            "elevation": round(r.view.elevation, 2),
            "pixels": r.pixels,
            **{
                f"{model}_{k}": round(m[k], 4)
                for model, m in r.metrics.items()
                for k in ("psnr", "flip")
            },
            "best": r.best,
        }
        for r in results
    ]


def spacing_sweep(
    scene: str = "room",
    steps: tuple[float, ...] = (40.0, 20.0, 10.0, 5.0),
    cameras: int = 4,
    size: int = 160,
    workers: int | None = None,
) -> dict:
    """Playback PSNR midway between samples against the grid spacing (module docstring).

    Returns
    -------
    dict
        ``rows``: per camera and spacing the models' PSNR and FLIP; ``mean``: per
        spacing the mean layered PSNR; ``chosen``: the coarsest spacing within 1 dB
        of the next denser one at every camera (None if none is).
    """
    scene_obj = load_scene(scene)
    base = scene_obj.camera
    picks = random_cameras(cameras, seed=7, lowest=15.0, highest=60.0)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        session = RenderSession(scene_obj, cube_size=128)
        try:
            method = session.method("pem")
            for c, (azimuth, elevation) in enumerate(picks):
                for step in steps:
                    start = time.perf_counter()
                    out = Path(tmp) / f"c{c}-s{step:g}.pem"
                    corner = (azimuth - step / 2, elevation - step / 2)
                    space = grid_views(base, 2, step, 2, step, start=corner)
                    run_bake(
                        scene, space, out, lookups="gl", gl_lookups=GlLookups, probe=False,
                        workers=workers, **ORBIT_BAKE,
                    )  # fmt: skip
                    method.values.update({"pem": str(out), "coverage": "file"})
                    method.prepare(session.gpu_scene)
                    (row,) = _measure(session, method, [(azimuth, elevation)], size)
                    rows.append(
                        {"camera": c, "step": step, **row, "seconds": time.perf_counter() - start}
                    )
        finally:
            session.release()
    mean = {s: float(np.mean([r["layered_psnr"] for r in rows if r["step"] == s])) for s in steps}
    chosen = None
    for coarse, fine in itertools.pairwise(steps):
        gaps = [
            fr["layered_psnr"] - cr["layered_psnr"]
            for cr in rows
            for fr in rows
            if cr["step"] == coarse and fr["step"] == fine and cr["camera"] == fr["camera"]
        ]
        if max(gaps) <= 1.0:
            chosen = coarse
            break
    return {"rows": rows, "mean_layered_psnr": mean, "chosen": chosen}


def orbit_quality(
    scene: str = "room",
    cameras: int = 24,
    size: int = 160,
    workers: int | None = None,
    em_size: int = ORBIT_BAKE["em_size"],
    fit: str = "refit",
    first: int | None = None,
    coupling: float = ORBIT_COUPLING,
) -> dict:
    """Layered, sphere, static EM and PTM of the full orbit at random cameras (module docstring).

    ``fit`` is pem's ``orbit_fit`` (``refit`` or ``seed003``), ``coupling`` its
    ``orbit_coupling``; ``first`` K measures the first K of the ``cameras`` alone (the
    same cameras as the whole set's first K).

    Returns
    -------
    dict
        ``rows`` per camera, ``summary`` per model the min / median / max of PSNR and
        FLIP, ``layered_leads`` whether the layered PEM has a higher PSNR than the
        sphere at infinity and the static EM at every camera (the issue's rule; the
        PTM is reported beside them), ``bake_seconds`` of the views baked for them
        (the PTM's 4 × 4 windows too).
    """
    picks = random_cameras(cameras)[:first]
    session = RenderSession(load_scene(scene), cube_size=128)
    try:
        method = session.method("pem")
        method.values.update({"coverage": "orbit", "orbit_em_size": str(em_size), "orbit_fit": fit})
        method.values["orbit_coupling"] = f"{coupling:g}"
        method.prepare(session.gpu_scene)
        store = method.orbit
        space, target = store.space, np.asarray(store.space["target"])
        needed = []
        for azimuth, elevation in picks:
            eye = OrbitCamera(azimuth=azimuth, elevation=elevation, target=target).position
            blend = view_blend(space, eye)
            needed += [v for v, w in zip(blend.views, blend.weights, strict=True) if w > 0]
            if "ptm" in store.shell().maps:
                needed += ptm_blend(space, eye).views
        start = time.perf_counter()
        views = list(dict.fromkeys(needed))
        report = store.bake(views, workers=workers, chunk=len(views))
        bake_seconds = time.perf_counter() - start
        rows = _measure(session, method, picks, size)
    finally:
        session.release()
    models = [m for m in ("layered", "sphere", "static", "ptm") if f"{m}_psnr" in rows[0]]
    summary = {
        f"{model}_{k}": [
            round(float(f(np.array([r[f"{model}_{k}"] for r in rows]))), 4)
            for f in (np.min, np.median, np.max)
        ]
        for model in models
        for k in ("psnr", "flip")
    }
    return {
        "rows": rows,
        "summary (min, median, max)": summary,
        "layered_leads": all(
            r["layered_psnr"] > max(r["sphere_psnr"], r["static_psnr"]) for r in rows
        ),
        "views_baked": len(report.baked),
        "bake_seconds": round(bake_seconds, 1),
        "trace_seconds_mean": round(float(np.mean(report.trace_seconds or [0.0])), 3),
        "infer_seconds_mean": round(float(np.mean(report.infer_seconds or [0.0])), 3),
    }


def orbit_wobble(
    scene: str = "room",
    start: tuple[float, float] = (22.0, 18.0),
    frames: int = 24,
    step: float = 0.25,
    size: int = 128,
    coupling: float | None = None,
) -> dict[str, float]:
    """Seed 003 §6's wobble and pops of the full orbit along an azimuth sweep.

    ``frames`` frames ``step`` degrees apart from ``start`` (azimuth, elevation): the
    default crosses the sample at 25° on the row at 18°. Per model and ``trace`` the
    mean frame-to-frame change (the wobble) and, as ``"<model> max"``, the largest (a
    pop where the sweep crosses a sample: the PTM's window moves on there).
    ``coupling`` is pem's ``orbit_coupling`` (None: its default).
    """
    session = RenderSession(load_scene(scene), cube_size=128)
    try:
        method = session.method("pem")
        method.values["coverage"] = "orbit"
        if coupling is not None:
            method.values["orbit_coupling"] = f"{coupling:g}"
        method.prepare(session.gpu_scene)
        changes = offmanifold.wobble_sweep(
            session, method, frames=frames, step=step, size=size, start=start
        )
    finally:
        session.release()
    out = {name: round(float(np.mean(c)), 5) for name, c in changes.items()}
    out.update({f"{name} max": round(float(np.max(c)), 5) for name, c in changes.items()})
    return out


def main(argv: list[str] | None = None) -> int:
    """Print :func:`spacing_sweep` or :func:`orbit_quality` as JSON."""
    parser = argparse.ArgumentParser(prog="python studies/pem-orbit/orbit_numbers.py")
    parser.add_argument("--scene", default="room")
    parser.add_argument("--spacing", metavar="S,S,...", help="spacings to sweep, degrees")
    parser.add_argument("--orbit", action="store_true", help="the full orbit at random cameras")
    parser.add_argument("--cameras", type=int)
    parser.add_argument("--size", type=int, default=160)
    parser.add_argument("--workers", type=int)
    parser.add_argument("--em-size", type=int, default=ORBIT_BAKE["em_size"], help="--orbit")
    parser.add_argument("--fit", choices=("refit", "seed003"), default="refit", help="--orbit")
    parser.add_argument("--first", type=int, help="--orbit: the first K of the cameras alone")
    parser.add_argument("--coupling", type=float, help="--orbit, --wobble: pem's orbit_coupling")
    parser.add_argument(
        "--wobble", metavar="AZ,EL", help="the orbit's wobble along 6° of azimuth from AZ, EL"
    )
    args = parser.parse_args(argv)
    if args.wobble:
        azimuth, elevation = (float(v) for v in args.wobble.split(","))
        out = orbit_wobble(args.scene, (azimuth, elevation), size=args.size, coupling=args.coupling)
    elif args.spacing:
        steps = tuple(float(s) for s in args.spacing.split(","))
        out = spacing_sweep(args.scene, steps, args.cameras or 4, args.size, args.workers)
    else:
        out = orbit_quality(
            args.scene, args.cameras or 24, args.size, args.workers, args.em_size, args.fit,
            args.first, ORBIT_COUPLING if args.coupling is None else args.coupling,
        )  # fmt: skip
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
