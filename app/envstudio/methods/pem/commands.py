"""``envstudio bake pem``: seed 003's per-view environment maps baked to a ``.pem`` file.

Bad input (a view count below 1, a non-positive step, views that would coincide,
a size out of range, an unknown scene, a scene without a reflector, a missing
output folder, a ``--scheduler`` that does not answer) is refused with one line
before any tracing. Views are baked on a local process pool or a Dask cluster and
saved one by one to ``OUT.pem.parts/``; a rerun resumes from there, and
``OUT.pem`` is written atomically only when every view is done (methods/pem/bake/bake.py).
The last line gives the mean predicted-playback PSNR of each model
(methods/pem/bake/models.py).
"""

from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np
from tqdm import tqdm

from envstudio.errors import OutputFileError
from envstudio.io.atomic import check_output_path
from envstudio.io.memory import available_memory
from envstudio.io.scene_file import load_scene, resolve_scene
from envstudio.methods.pem.bake import bake
from envstudio.methods.pem.bake.bake import BakeReport, parts_folder
from envstudio.methods.pem.bake.lookups import PLAYBACK
from envstudio.methods.pem.bake.orbit import ORBIT_STEP
from envstudio.methods.pem.bake.views import (
    ViewSpace,
    arc_views,
    grid_views,
    orbit_views,
    uncovered,
)
from envstudio.methods.pem.lookups_gl import GlLookups
from envstudio.plugin import Bake, ParameterError
from envstudio.scene.camera import OrbitCamera

__all__ = ["BAKE", "DEFAULTS", "add_bake_arguments", "run_bake", "run_bake_pem"]

#: Defaults of the bake's sizes (seed 003 §6: 100 views at 1°).
DEFAULTS = {"views": 100, "step": 1.0, "size": 256, "samples": 4, "em_size": 64, "workers": None}


def run_bake(*args, **kwargs) -> BakeReport:
    """:func:`envstudio.methods.pem.bake.bake.run_bake` with the playback shader's GL lookups
    (:class:`~envstudio.methods.pem.lookups_gl.GlLookups`) where a context can be made."""
    return bake.run_bake(*args, gl_lookups=GlLookups, **kwargs)


def add_bake_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``envstudio bake pem``."""
    parser.add_argument("--scene", help="shipped scene name (room) or a TOML scene file")
    parser.add_argument("--env", help=argparse.SUPPRESS)  # refused: the scene's is baked
    parser.add_argument("--size", type=int, help="trace resolution R (256)")
    parser.add_argument("--views", type=int, help="views on the arc (100)")
    parser.add_argument("--step", type=float, help="degrees between views (default 1)")
    parser.add_argument("--samples", type=int, help="rays per pixel (4)")
    parser.add_argument("--em-size", type=int, help="cube face edge of the EMs (default 64)")
    parser.add_argument(
        "--elevations",
        type=int,
        default=1,
        help="rows of a 2D view grid, --elevation-step apart from the scene camera's (1: arc)",
    )
    parser.add_argument(
        "--elevation-step", type=float, default=5.0, help="degrees between grid rows (5)"
    )
    parser.add_argument(
        "--tie",
        type=float,
        help="weight μ of the coarse-to-fine MIP ties (default 1e-3; larger: coarse levels "
        "nearer the decimated finest, steadier at small playback sizes, studies/pem-bake)",
    )
    parser.add_argument(
        "--coupling",
        type=float,
        default=0.0,
        help="coupled inference (not in seed 003): weight γ tying each view's maps to its "
        "neighbours' (0: each view alone, as the paper; studies/pem-bake)",
    )
    parser.add_argument(
        "--coupling-passes",
        type=int,
        default=2,
        help="coupled passes after the independent one (2)",
    )
    parser.add_argument(
        "--phong-exponent",
        type=float,
        default=None,
        metavar="N",
        help="glossy reflectors (not in seed 003, whose §7 leaves them open): trace with the "
        "Phong lobe of exponent N sampled at each hit, as the reference's lobe (default: "
        "mirrors; studies/pem-bake)",
    )
    parser.add_argument(
        "--rtol",
        type=float,
        help="the MIP solves' conjugate-gradient tolerance (default 1e-6 below 128² EMs, 1e-4 "
        "from 128², where the multigrid solves; 1e-4 is about twice as fast with the same "
        "playback to 0.08 dB, studies/pem-paper-scale/README.md)",
    )
    parser.add_argument(
        "--over-passes",
        type=int,
        default=0,
        metavar="K",
        help="refit the layered model's distant and local colour through its composite K "
        "times after seed 003's sequential fit (not in the paper; studies/pem-orbit/README.md); "
        "default 0",
    )
    parser.add_argument(
        "--footprints",
        type=int,
        default=1,
        metavar="F",
        help="fit every level to the view at R, R/2, ..., R/2^(F-1) too, so that a smaller "
        "playback reads fitted levels (not in the paper; studies/pem-orbit/README.md); default 1",
    )
    parser.add_argument(
        "--zstd-level",
        type=int,
        default=19,
        metavar="L",
        help="the file's zstd level, 1-22 (default 19: small, slow; 3 writes 5%% more in a "
        "26th of the time, for big bakes; studies/pem-paper-scale/README.md)",
    )
    parser.add_argument(
        "--no-ptm",
        dest="ptm",
        action="store_false",
        help="skip the PTM's per-view surface textures (seed 003 Figure 7)",
    )
    parser.add_argument(
        "--lookups",
        choices=("auto", "gl", "cpu"),
        default="auto",
        help="build A from the playback shader's own lookups on GL (auto: when a context "
        "can be made) or from pixel-centre rays on the CPU",
    )
    parser.add_argument(
        "--workers", type=int, help="local processes (default one per core; 0 in-process)"
    )
    cluster = parser.add_mutually_exclusive_group()
    cluster.add_argument(
        "--dask",
        dest="scheduler",
        action="store_const",
        const="local",
        help="bake on a local Dask cluster (2 worker processes) instead of the pool",
    )
    cluster.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="bake on the Dask scheduler at ADDRESS (tcp://host:8786), or 'local'",
    )


def _check(args: argparse.Namespace) -> None:
    if args.env is not None:
        raise ParameterError("bake pem: --env is not used (the scene's environment is baked)")
    tie = getattr(args, "tie", None)
    if tie is not None and not (math.isfinite(tie) and 0.0 <= tie <= 10.0):
        raise ParameterError(f"--tie {tie:g}: expected a weight in [0, 10]")
    coupling = getattr(args, "coupling", 0.0)
    if not (math.isfinite(coupling) and 0.0 <= coupling <= 100.0):
        raise ParameterError(f"--coupling {coupling:g}: expected a weight in [0, 100]")
    if getattr(args, "coupling_passes", 2) < 1:
        raise ParameterError(f"--coupling-passes {args.coupling_passes}: expected at least 1")
    exponent = getattr(args, "phong_exponent", None)
    if exponent is not None and not (math.isfinite(exponent) and 0.0 < exponent <= 1e7):
        raise ParameterError(f"--phong-exponent {exponent:g}: expected an exponent in (0, 1e7]")
    rtol = getattr(args, "rtol", None)
    if rtol is not None and not (math.isfinite(rtol) and 0.0 < rtol < 1.0):
        raise ParameterError(f"--rtol {rtol:g}: expected a relative residual in (0, 1)")
    if not 0 <= getattr(args, "over_passes", 0) <= 20:
        raise ParameterError(f"--over-passes {args.over_passes}: expected 0 to 20")
    if not 1 <= getattr(args, "zstd_level", 19) <= 22:
        raise ParameterError(f"--zstd-level {args.zstd_level}: expected a level in [1, 22]")
    if getattr(args, "elevations", 1) < 1:
        raise ParameterError(f"--elevations {args.elevations}: expected a row count ≥ 1")
    if args.views < 1:
        raise ParameterError(f"--views {args.views}: expected a view count ≥ 1")
    if not (math.isfinite(args.step) and args.step > 0):
        raise ParameterError(f"--step {args.step:g}: expected a positive number of degrees")
    if not 8 <= args.size <= 4096:
        raise ParameterError(f"--size {args.size}: expected a trace resolution in [8, 4096]")
    footprints = getattr(args, "footprints", 1)
    if not (1 <= footprints and args.size >> (footprints - 1) >= 8):
        raise ParameterError(
            f"--footprints {footprints}: expected 1 or more, with --size / 2^(F-1) ≥ 8"
        )
    if not 1 <= args.samples <= 1024:
        raise ParameterError(f"--samples {args.samples}: expected rays per pixel in [1, 1024]")
    if not 2 <= args.em_size <= 1024:
        raise ParameterError(f"--em-size {args.em_size}: expected a cube face edge in [2, 1024]")
    if args.workers is not None and args.workers < 0:
        raise ParameterError(f"--workers {args.workers}: expected 0 (in-process) or more")


#: Bytes a worker holds per scene triangle (Embree's BVH, the hull and the mesh arrays).
BYTES_PER_TRIANGLE = 512
#: Vectors of the size of a view's unknowns the least-squares solve keeps (float64).
SOLVE_VECTORS = 12


def memory_estimate(scene, views: int, args: argparse.Namespace, workers: int) -> dict:
    """A bake's peak memory, bytes: its workers' and, at the end, the whole bake's maps.

    Per worker: the scene's triangles (:data:`BYTES_PER_TRIANGLE`), the solve's
    vectors over one view's unknowns (every level of every part's maps: 10 channels
    over seed 003's three models, 13 with the PTM) and the trace's rays (R² × samples
    × 256 bytes). The parent assembles every view's float32 maps before writing the file. A coarse
    upper bound, for refusing a bake that cannot fit (issue 31, "Bad input").
    """
    triangles = sum(node.mesh.triangle_count for node in scene.nodes)
    parts = len(scene.reflectors())
    texels = sum(6 * (args.em_size >> k) ** 2 for k in range(int(np.log2(args.em_size)) + 1))
    unknowns = parts * texels * (13 if getattr(args, "ptm", True) else 10)  # PTM: 3 more
    worker = triangles * BYTES_PER_TRIANGLE + SOLVE_VECTORS * unknowns * 8
    worker += args.size**2 * args.samples * 256
    return {"workers": workers * worker, "maps": views * unknowns * 4, "worker": worker}


def _check_memory(args: argparse.Namespace, views: int) -> None:
    """Refuse, in one line with the estimate, a bake that would not fit in memory."""
    scene = load_scene(args.scene)
    workers = (os.cpu_count() or 1) if args.workers is None else max(1, args.workers)
    need = memory_estimate(scene, views, args, min(workers, views))
    total, available = need["workers"] + need["maps"], available_memory()
    if total > available:
        mb, triangles = 2**20, sum(n.mesh.triangle_count for n in scene.nodes)
        raise ParameterError(
            f"bake pem: about {total / mb:,.0f} MB needed ({min(workers, views)} workers × "
            f"{need['worker'] / mb:,.0f} MB for {triangles:,} "
            f"triangles and {args.em_size}² EMs, and {need['maps'] / mb:,.0f} MB of maps for "
            f"{views} views), {available / mb:,.0f} MB available: use a coarser mesh, fewer "
            "--views, a smaller --em-size or fewer --workers"
        )


def _coverage_warning(space: ViewSpace, camera: OrbitCamera) -> str:
    """One line: which of the scene's orbit cameras the bake's views leave outside (issue 31)."""
    cameras = orbit_views(camera, *ORBIT_STEP).cameras()
    outside = uncovered(space, cameras)
    az, el = space.azimuths, space.elevations
    return (
        f"envstudio: warning: the views cover azimuth {az.min():g}°…{az.max():g}° and elevation "
        f"{el.min():g}°…{el.max():g}°: {len(outside)} of {len(cameras)} orbit cameras "
        f"({ORBIT_STEP[0]:g}° × {ORBIT_STEP[1]:g}° apart) lie outside and play the nearest edge "
        "views; pem's coverage=orbit plays every one (studies/pem-orbit/README.md)"
    )


def _saved(out, args: argparse.Namespace) -> str:
    """How many views are saved in the parts folder, and that the same command resumes."""
    folder = parts_folder(out)
    saved = len(list(folder.glob("view-*.npz"))) if folder.is_dir() else 0
    total = args.views * getattr(args, "elevations", 1)
    return f"{saved} of {total} views saved in {folder}/, the same command resumes"


def run_bake_pem(args: argparse.Namespace) -> int:
    """Check the arguments, bake with a progress bar, write the file, print one line."""
    for name, value in DEFAULTS.items():
        if getattr(args, name, None) is None:
            setattr(args, name, value)
    _check(args)
    if args.scene is None:
        raise ParameterError("bake pem: --scene is required (a shipped name or a TOML file)")
    out = check_output_path(args.output, (".pem",))
    resolve_scene(args.scene)
    elevations = getattr(args, "elevations", 1)

    def views(camera: OrbitCamera):
        if elevations > 1:
            return grid_views(camera, args.views, args.step, elevations, args.elevation_step)
        return arc_views(camera, args.views, args.step)

    try:
        views(OrbitCamera())  # views that coincide, elevations past ±89°: before any work
    except ValueError as exc:
        raise ParameterError(str(exc)) from None
    _check_memory(args, args.views * elevations)
    with tqdm(unit="view", desc="pem", leave=False, disable=not sys.stderr.isatty()) as bar:
        try:
            report = run_bake(
                args.scene,
                views,
                out,
                size=args.size,
                samples=args.samples,
                em_size=args.em_size,
                workers=args.workers,
                bar=bar,
                scheduler=getattr(args, "scheduler", None),
                lookups=getattr(args, "lookups", "auto"),
                tie=getattr(args, "tie", None),
                ptm=getattr(args, "ptm", True),
                coupling=getattr(args, "coupling", 0.0),
                coupling_passes=getattr(args, "coupling_passes", 2),
                rtol=getattr(args, "rtol", None),
                over_passes=getattr(args, "over_passes", 0),
                footprints=getattr(args, "footprints", 1),
                zstd_level=getattr(args, "zstd_level", 19),
                phong_exponent=getattr(args, "phong_exponent", None),
            )
        except ValueError as exc:  # a scene without a reflector, a scheduler that is silent
            raise ParameterError(str(exc)) from None
        except KeyboardInterrupt:
            bar.write(f"envstudio: {out}: not written; {_saved(out, args)}", file=sys.stderr)
            raise
        except OutputFileError as exc:  # a full disk: the views baked so far are kept
            raise OutputFileError(f"{exc}; {_saved(out, args)} once there is room") from None
    bake = report.bake
    resumed = f", {len(report.reused)} resumed" if report.reused else ""
    scores = ", ".join(
        f"{name} {np.nanmean(bake.playback_psnr[name]):.1f}"
        for name in PLAYBACK
        if name in bake.playback_psnr
    )
    print(
        f"{out}: {bake.views} views × {len(bake.parts)} parts, {bake.em_size}² EMs in "
        f"{bake.levels} levels ({len(report.baked)} baked{resumed}) in {report.seconds:.1f} s; "
        f"playback PSNR {scores} dB"
    )
    camera = load_scene(args.scene).camera
    print(_coverage_warning(views(camera), camera), file=sys.stderr)
    return 0


BAKE = Bake(
    "pem",
    "seed 003's per-view environment maps of a scene, ray traced and inferred, to FILE.pem",
    run_bake_pem,
    add_bake_arguments,
)
