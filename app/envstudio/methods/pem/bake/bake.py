"""The PEM bake as a job: one work unit per view, saved as it finishes, resumable (seed 003 §3).

Seed 003 §3 ("System Overview") ray traces and infers EMs independently for
every sample of the parameter space, so a view is the work unit:
:func:`bake_view` takes a picklable :class:`ViewTask` and returns plain arrays
(it builds and caches the scene's tracer in its own process), so the same unit
runs in-process, on a local process pool (:func:`run_bake`, concurrent.futures)
or on a Dask cluster (``scheduler``: a scheduler address, or ``"local"`` for a
``dask.distributed.LocalCluster`` of two worker processes; the ``cluster`` extra).

Resume: every finished view is written atomically to ``OUT.pem.parts/view-NNNNN.npz``
(its arrays, a checksum, and the key of the bake it belongs to: scene file,
environment pixels, parameters and camera). A rerun verifies and reuses the
parts whose key matches and redoes the rest. ``OUT.pem`` (:mod:`.pem_file`) is
written atomically only when every view is present and verified, then the parts
folder is removed; an interrupted bake leaves nothing under ``OUT.pem``.

Coupled inference (issue 31; not in seed 003): with a coupling weight γ > 0,
after the independent pass every view is inferred again ``coupling_passes``
times, drawn towards the mean of its neighbours' latest maps (red-black
Gauss–Seidel passes of the joint least squares,
:mod:`~envstudio.methods.pem.bake.infer`: first the views of even index sum
(elevation row + azimuth column), whose neighbours are all odd, then the odd
ones with the even ones' new maps; plain Jacobi passes, every view from the pass
before, oscillate for large γ). The neighbours are the adjacent views of the arc,
or the four of a grid. Each half pass is again one work unit per view, run in
parallel, saved as ``view-NNNNN-pass-K.npz`` and resumable. γ = 0 runs the independent
pass alone, with the parameters of a bake made before the option existed: the
same file, bit for bit.

Glossy reflectors (issue 31 part 5; seed 003 §7 leaves them "to be
investigated"): with ``phong_exponent`` N > 0 every view is traced with the
reflectors' Phong lobe of exponent N sampled at each hit
(:mod:`~envstudio.methods.pem.bake.trace`), and its maps are inferred as for a
mirror, for the playback's trilinear lookups along r. Unset (None or 0): the
mirror, with the parameters, parts and file of a bake made before the option.
"""

from __future__ import annotations

import hashlib
import json
import multiprocessing
import os
import shutil
import signal
import time
import zipfile
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np

from envstudio.io.atomic import atomic_path, check_output_path
from envstudio.io.cluster import dask_client
from envstudio.io.scene_file import load_scene, resolve_scene
from envstudio.methods.pem.bake.hull import mesh_check, reflector_hulls
from envstudio.methods.pem.bake.infer import MULTIGRID_SIZE, distant_box, local_ellipsoid
from envstudio.methods.pem.bake.lookups import (
    LOD_BIAS,
    MODELS,
    PLAYBACK,
    REQUIRED,
    PixelLookups,
    pixel_lookups,
)
from envstudio.methods.pem.bake.mip import mip_sizes
from envstudio.methods.pem.bake.models import infer_view_models, playback_psnr, predict, static_em
from envstudio.methods.pem.bake.pem_file import FORMAT, VERSION, PemBake, save_pem
from envstudio.methods.pem.bake.trace import TRACE_BOUNCES, SceneTracer
from envstudio.methods.pem.bake.views import ViewSpace
from envstudio.scene.camera import OrbitCamera

__all__ = [
    "DASK_CONNECT_TIMEOUT",
    "MULTIGRID_RTOL",
    "SOLVE_RTOL",
    "BakePlan",
    "BakeReport",
    "ViewTask",
    "bake_tasks",
    "bake_view",
    "default_rtol",
    "load_part",
    "neighbour_anchors",
    "neighbours",
    "part_keys",
    "part_name",
    "parts_folder",
    "plan_bake",
    "run_bake",
]

#: The MIP solves' default CG tolerance (infer.py ``solve_mip``): bakes' of before the option.
SOLVE_RTOL = 1e-6

#: The default tolerance where the solve is the multigrid one (from ``MULTIGRID_SIZE``² EMs,
#: whose parts were never those of before): at 256² EMs its playback is 10⁻⁶'s to 0.015 dB
#: at the sample views and midway between them, in half the inference
#: (studies/pem-paper-scale/README.md).
MULTIGRID_RTOL = 1e-4

#: Seconds a ``--scheduler ADDRESS`` has to answer before the bake gives up.
DASK_CONNECT_TIMEOUT = 10.0


def part_keys(em_size: int, models: tuple[str, ...] = MODELS) -> list[str]:
    """Names of a view's arrays (:func:`bake_view`) saved in its part file."""
    keys = [f"{m}_{k}" for m in models for k in range(len(mip_sizes(em_size)))]
    names = [n for n in PLAYBACK if n != "ptm" or "ptm" in models]
    return keys + [f"psnr_{m}" for m in models] + [f"playback_{n}" for n in names]


def neighbours(view_space: dict) -> list[list[int]]:
    """Each view's neighbours on its parameter grid (coupled inference, module docstring).

    Parameters
    ----------
    view_space
        ``ViewSpace.describe()``: views are elevation-major, ``len(azimuths)`` a row.

    Returns
    -------
    list of list of int
        Per view, the adjacent views along the azimuths (an arc does not close:
        its ends have one; a full orbit's azimuths do, across 360°) and, on a grid,
        along the elevations.
    """
    count = len(view_space["azimuths"])
    rows = len(view_space["elevations"]) if view_space.get("kind") == "grid" else 1
    closed = bool(view_space.get("closed", False)) and count > 2
    out = []
    for e in range(rows):
        for a in range(count):
            near = [(e, a - 1), (e, a + 1), (e - 1, a), (e + 1, a)]
            if closed:
                near = [(r, c % count) for r, c in near]
            out.append([r * count + c for r, c in near if 0 <= r < rows and 0 <= c < count])
    return out


@dataclass(frozen=True)
class ViewTask:
    """One work unit: trace one view and infer each part's EM models, all MIP levels.

    Attributes
    ----------
    scene : str
        Resolved scene file path (each worker loads and caches it).
    index : int
        The view's position in ``ViewSpace.cameras()``.
    azimuth, elevation, distance : float
        Orbit camera, degrees and scene units.
    target : tuple of float
    fov_y : float
    size, samples : int
        Trace resolution R and rays per pixel.
    em_size : int
        Cube face edge n.
    smoothness : float
        λ of :func:`~envstudio.methods.pem.bake.infer.solve_mip`.
    seed : int
        Jitter seed; the view traces with ``seed + index``.
    tie : float
        μ of :func:`~envstudio.methods.pem.bake.infer.solve_mip` (coarse-to-fine ties).
    lod_bias : float
        Added to every lookup's MIP level (:data:`~envstudio.methods.pem.bake.lookups.LOD_BIAS`).
    lookups : str
        ``gl``: the per-pixel lookups rendered by the playback shader itself
        (``gl_lookups``), so that A is the playback's on this GL; ``cpu``:
        computed from pixel-centre rays (methods/pem/bake/lookups.py), the same up
        to the level, which the GL takes from its own derivatives.
    gl_lookups : type or None
        The GL lookups' class (methods/pem/lookups_gl.py's ``GlLookups``), which a
        worker imports by name when it unpickles the task: the bake itself never
        imports GL.
    models : tuple of str
        The maps to infer (:data:`~envstudio.methods.pem.bake.lookups.MODELS`; without
        ``ptm``: the three of seed 003 alone, as bakes before issue 31).
    coupling : float
        γ of coupled inference (module docstring; not in seed 003); 0: independent.
    coupling_pass : int
        0 the independent pass, K ≥ 1 the K-th coupled pass.
    anchors : dict or None
        For a coupled pass: model → per part None or (mean, count), the mean
        (Σ 6 n_k², C) of the ``count`` neighbours' maps of the pass before (derived
        from verified parts, so not part of the part's identity).
    phong_exponent : float
        N of the reflectors' Phong lobe sampled by the trace (module docstring);
        0: mirrors, as bakes before the option.
    rtol : float
        The conjugate gradient's relative residual in every MIP solve
        (default :func:`default_rtol`; studies/pem-paper-scale/README.md measures
        10⁻⁴: at 64² EMs (Jacobi) twice as fast with the same playback to 0.08 dB at the
        orbit's cameras, at 256² (multigrid) 22 s against 46 s a view; 10⁻³ loses up to
        1.6 dB between views).
    over_passes : int
        K ≥ 1: the layered model's distant and local colour refitted through its
        composite K times after seed 003's sequential fit (:mod:`.over`; not in seed
        003); 0: the paper's fit, as bakes before the option.
    footprints : int
        F ≥ 1: the view's rows at R, R/2, …, R/2^(F−1) in every solve (the trace
        box-filtered, its lookups at each size; models.py, not in seed 003); 1: the
        bake's own pixels alone, as bakes before the option.
    """

    scene: str
    index: int
    azimuth: float
    elevation: float
    distance: float
    target: tuple[float, float, float]
    fov_y: float
    size: int
    samples: int
    em_size: int
    smoothness: float
    seed: int
    tie: float = 1e-3
    lod_bias: float = LOD_BIAS
    lookups: str = "gl"
    gl_lookups: type | None = None
    models: tuple[str, ...] = MODELS
    coupling: float = 0.0
    coupling_pass: int = 0
    anchors: dict | None = None
    phong_exponent: float = 0.0
    rtol: float = 1e-6
    over_passes: int = 0
    footprints: int = 1

    def camera(self) -> OrbitCamera:
        """The view's camera."""
        return OrbitCamera(
            azimuth=self.azimuth,
            elevation=self.elevation,
            distance=self.distance,
            target=np.array(self.target, dtype=np.float64),
            fov_y=self.fov_y,
        )


_CONTEXTS: dict[str, dict] = {}


def _context(scene_path: str) -> dict:
    """The scene, its tracer and its view-independent bake data, once per process."""
    if scene_path not in _CONTEXTS:
        scene = load_scene(scene_path)
        tracer = SceneTracer(scene)
        local = [local_ellipsoid(tracer, p) for p in range(len(tracer.part_names))]
        _CONTEXTS[scene_path] = {
            "scene": scene,
            "tracer": tracer,
            "box": distant_box(scene),
            "ellipsoids": [g for g, _ in local],
            "origins": np.array([o for _, o in local]),
            "hull": reflector_hulls(scene),
            "static": {},
        }
    return _CONTEXTS[scene_path]


def _view_lookups(ctx: dict, task: ViewTask, camera: OrbitCamera) -> PixelLookups:
    """The playback's per-pixel lookups of the view, by ``task.lookups``."""
    box, ellipsoids, origins = ctx["box"], ctx["ellipsoids"], ctx["origins"]
    if task.lookups == "cpu":
        return pixel_lookups(
            ctx["tracer"], camera, task.size, task.em_size, box, ellipsoids, origins
        )
    if task.gl_lookups is None:
        raise ValueError("a view task with lookups 'gl' needs gl_lookups (GlLookups)")
    if "gl" not in ctx:
        ctx["gl"] = task.gl_lookups(ctx["scene"])  # one headless context per worker process
    return ctx["gl"].render(
        camera,
        task.size,
        task.em_size,
        np.array([box.lo, box.hi]),
        origins,
        np.array([[e.centre, e.radii] for e in ellipsoids]),
    )


def resolve_lookups(lookups: str, gl_lookups: type | None) -> str:
    """``auto`` → ``gl`` when ``gl_lookups`` can make a GL context here, else ``cpu``.

    Parameters
    ----------
    lookups
        ``auto``, ``gl`` or ``cpu``.
    gl_lookups
        The GL lookups' class, whose ``unavailable()`` says why no context can be
        made (None when one can); None: no GL here.

    Raises
    ------
    ValueError
        An unknown choice, or ``gl`` where no context can be made.
    """
    if lookups not in ("auto", "gl", "cpu"):
        raise ValueError(f"--lookups {lookups}: expected auto, gl or cpu")
    if lookups == "cpu":
        return "cpu"
    reason = "no GL lookups given" if gl_lookups is None else gl_lookups.unavailable()
    if reason is None:
        return "gl"
    if lookups == "gl":
        raise ValueError(f"--lookups gl: no GL context ({reason}); use --lookups cpu")
    return "cpu"


def bake_view(task: ViewTask) -> dict[str, np.ndarray]:
    """Trace one view and infer every part's EM models (seed 003 §4, methods/pem/bake/models.py).

    Parameters
    ----------
    task
        The work unit.

    Returns
    -------
    dict
        ``{model}_{k}`` (P, 6, n_k, n_k, C) float32 for each model of
        :data:`~envstudio.methods.pem.bake.lookups.MODELS` and level k (0 for a part not
        in the view), ``psnr_{model}`` (P,) float64 fit PSNR (NaN for such a part),
        ``playback_{name}`` 0-d float64 predicted playback PSNR for ``layered``,
        ``sphere``, ``static``, and ``trace_seconds``, ``infer_seconds`` (0-d
        float64; inference includes the lookups and the predictions).
    """
    ctx = _context(task.scene)
    tracer, n = ctx["tracer"], task.em_size
    camera = task.camera()
    view = tracer.trace(
        camera, task.size, task.samples, task.seed + task.index, task.phong_exponent or None
    )
    start = time.perf_counter()
    lookups = _view_lookups(ctx, task, camera)
    coarser: list = []
    for _ in range(task.footprints - 1):
        smaller = (coarser[-1][0] if coarser else view).halved()
        coarser.append((smaller, _view_lookups(ctx, replace(task, size=smaller.size), camera)))
    coupled = {}
    if task.coupling and task.anchors is not None:
        coupled = {"anchors": task.anchors, "coupling": task.coupling}
    models = infer_view_models(
        view,
        lookups,
        n,
        ctx["hull"],
        smoothness=task.smoothness,
        tie=task.tie,
        lod_bias=task.lod_bias,
        models=tuple(task.models),
        rtol=task.rtol,
        over_passes=task.over_passes,
        coarser=tuple(coarser),
        **coupled,
    )
    if n not in ctx["static"]:
        ctx["static"][n] = static_em(tracer, ctx["scene"].reflector_centre(), n)
    predicted = predict(view, lookups, models, n, ctx["hull"], ctx["static"][n])
    scores = playback_psnr(view, lookups, predicted)
    out: dict[str, np.ndarray] = {}
    for model in task.models:
        for k, level in enumerate(models.maps(model, n)):
            out[f"{model}_{k}"] = level
        out[f"psnr_{model}"] = models.psnr(model)
    for name in scores:
        out[f"playback_{name}"] = np.array(scores[name], dtype=np.float64)
    out["trace_seconds"] = np.array(view.seconds)
    out["infer_seconds"] = np.array(time.perf_counter() - start)
    return out


@dataclass
class BakeReport:
    """What :func:`run_bake` did.

    Attributes
    ----------
    bake : PemBake
        The bake written.
    path : Path
        The ``.pem`` file.
    baked, reused : list of int
        View indices traced in this run, and taken from the parts folder.
    seconds : float
        Wall time.
    trace_seconds, infer_seconds : list of float
        Per view baked in this run.
    """

    bake: PemBake
    path: Path
    baked: list[int] = field(default_factory=list)
    reused: list[int] = field(default_factory=list)
    seconds: float = 0.0
    trace_seconds: list[float] = field(default_factory=list)
    infer_seconds: list[float] = field(default_factory=list)


def parts_folder(output: str | os.PathLike) -> Path:
    """The resume folder of a bake to ``output``: ``output`` + ``.parts``."""
    return Path(f"{output}.parts")


def _bake_key(scene_path: Path, scene, parameters: dict) -> str:
    digest = hashlib.sha256(f"{FORMAT} {VERSION}".encode())
    digest.update(scene_path.read_bytes())
    digest.update(np.ascontiguousarray(scene.environment.radiance, np.float32).tobytes())
    digest.update(json.dumps(parameters, sort_keys=True).encode())
    return digest.hexdigest()


def _part_checksum(arrays: dict[str, np.ndarray], header: dict) -> str:
    digest = hashlib.sha256(json.dumps(header, sort_keys=True).encode())
    models = tuple(header["task"].get("models", REQUIRED))
    for name in part_keys(header["task"]["em_size"], models):
        digest.update(np.ascontiguousarray(arrays[name]).tobytes())
    return digest.hexdigest()


def _part_header(key: str, task: ViewTask) -> dict:
    """The part's identity: the bake's key and the task (its GL lookups' class is how, not what)."""
    skip = ("gl_lookups", "anchors")  # how, and what verified parts determine
    names = [f.name for f in fields(task) if f.name not in skip]
    task_fields = {k: getattr(task, k) for k in names}
    task_fields["models"] = list(task.models)
    if not task.coupling:  # the independent pass: the identity of parts before issue 31
        del task_fields["coupling"], task_fields["coupling_pass"]
    if tuple(task.models) == REQUIRED:
        del task_fields["models"]
    if not task.phong_exponent:  # a mirror: the identity of parts before issue 31 part 5
        del task_fields["phong_exponent"]
    if task.rtol == SOLVE_RTOL:  # the solve of before the option
        del task_fields["rtol"]
    if task.em_size >= MULTIGRID_SIZE:  # infer.py's multigrid CG: not the bits of before
        task_fields["solver"] = "multigrid"
    if not task.over_passes:  # seed 003's sequential layered fit, as before the option
        del task_fields["over_passes"]
    if task.footprints == 1:  # the bake's own pixels alone, as before the option
        del task_fields["footprints"]
    return {"key": key, "task": task_fields}


def _save_part(path: Path, key: str, task: ViewTask, result: dict) -> None:
    arrays = {k: np.array(result[k], order="C") for k in part_keys(task.em_size, task.models)}
    header = _part_header(key, task)
    meta = {"header": header, "checksum": _part_checksum(arrays, header)}
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            np.savez(f, meta=np.array(json.dumps(meta, sort_keys=True)), **arrays)


def load_part(path: Path, key: str, task: ViewTask) -> dict | None:
    """The part's arrays if it is readable, of this bake and view, and intact; else None."""
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            arrays = {k: np.asarray(data[k]) for k in part_keys(task.em_size, task.models)}
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
        return None
    header = _part_header(key, task)
    if json.loads(json.dumps(header)) != meta.get("header"):
        return None
    if meta.get("checksum") != _part_checksum(arrays, header):
        return None
    return arrays


def _ignore_interrupts() -> None:  # worker initializer: the parent handles Ctrl-C
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _map_local(tasks, workers: int):
    """Yield (task, result) as views finish, in-process (workers 0) or on a process pool."""
    if workers == 0:
        for task in tasks:
            yield task, bake_view(task)
        return
    context = multiprocessing.get_context("spawn")  # no fork after Embree's threads start
    pool = ProcessPoolExecutor(workers, mp_context=context, initializer=_ignore_interrupts)
    pending = {pool.submit(bake_view, t): t for t in tasks}
    try:
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                yield pending.pop(future), future.result()
    except BaseException:
        for future in pending:
            future.cancel()
        for process in list(getattr(pool, "_processes", {}).values()):
            process.terminate()
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


def _map_dask(tasks, client):
    """Yield (task, result) as views finish on a Dask cluster."""
    from dask.distributed import as_completed

    futures = {client.submit(bake_view, t, pure=False): t for t in tasks}
    try:
        for future in as_completed(futures):
            yield futures[future], future.result()
    except BaseException:
        client.cancel(list(futures))
        raise


@dataclass
class BakePlan:
    """What a bake will do (:func:`plan_bake`), before any work.

    Attributes
    ----------
    scene : Scene
        The loaded scene.
    tracer : SceneTracer
        Its tracer (built here: a scene without a reflector is refused first).
    space : ViewSpace
        The parameter space.
    parameters : dict
        The bake's parameters as stored in its file.
    key : str
        The identity its parts are saved under (scene file, environment pixels,
        parameters, view space).
    tasks : list of ViewTask
        One per view, in view order.
    models : tuple of str
        The maps inferred.
    coupling : float
        γ of coupled inference.
    """

    scene: object
    tracer: SceneTracer
    space: ViewSpace
    parameters: dict
    key: str
    tasks: list
    models: tuple
    coupling: float


def default_rtol(em_size: int) -> float:
    """The MIP solves' CG tolerance when none is given: :data:`MULTIGRID_RTOL` where the
    multigrid solves (``em_size`` ≥ ``MULTIGRID_SIZE``), else :data:`SOLVE_RTOL`."""
    return MULTIGRID_RTOL if em_size >= MULTIGRID_SIZE else SOLVE_RTOL


def plan_bake(
    scene, views, size=256, samples=4, em_size=64, smoothness=1e-3, seed=0, tie=None,
    lod_bias=LOD_BIAS, lookups="auto", gl_lookups=None, ptm=True, coupling=0.0, coupling_passes=2,
    probe=True, phong_exponent=None, rtol=None, over_passes=0, footprints=1,
) -> BakePlan:  # fmt: skip
    """The tasks, parameters and key of a bake (:func:`run_bake`'s arguments; no work done).

    ``probe`` False takes ``lookups`` (``gl`` or ``cpu``) as it is, without making a
    GL context to see whether one can be made: a process that holds a context (the
    viewer) must not make and release another.

    ``phong_exponent`` N > 0 samples the reflectors' Phong lobe in the trace
    (module docstring); None or 0: mirrors, and the parameters and key of before.
    ``rtol`` is the MIP solves' CG tolerance (:class:`ViewTask`); None:
    :func:`default_rtol` (below 128² EMs the parameters and key of before). ``over_passes`` K ≥ 1
    refits the layered model through its composite and ``footprints`` F > 1 adds the
    view's coarser footprints to the solves (:class:`ViewTask`); 0 and 1: the
    parameters and key of before.

    Raises
    ------
    ValueError
        A scene without a reflector, ``gl`` lookups without a context, a negative
        coupling weight or no coupled pass for a positive one, a Phong exponent
        that is negative or not finite.
    """
    scene_path = resolve_scene(scene)
    scene_obj = load_scene(scene_path)
    tracer = SceneTracer(scene_obj)  # raises ValueError for a scene without a reflector
    space = views if isinstance(views, ViewSpace) else views(scene_obj.camera)
    tie = float(smoothness if tie is None else tie)
    lookups = resolve_lookups(lookups, gl_lookups) if probe else lookups
    coupling = float(coupling)
    if not (np.isfinite(coupling) and coupling >= 0.0):
        raise ValueError(f"coupling {coupling:g}: expected a weight ≥ 0")
    if coupling and int(coupling_passes) < 1:
        raise ValueError(f"coupling passes {coupling_passes}: expected at least 1")
    exponent = float(phong_exponent or 0.0)
    if not (np.isfinite(exponent) and exponent >= 0.0):
        raise ValueError(f"phong exponent {exponent:g}: expected N > 0, or 0 for a mirror")
    rtol = default_rtol(int(em_size)) if rtol is None else float(rtol)
    if not (np.isfinite(rtol) and 0.0 < rtol < 1.0):
        raise ValueError(f"rtol {rtol:g}: expected a relative residual in (0, 1)")
    over_passes = int(over_passes)
    if over_passes < 0:
        raise ValueError(f"over passes {over_passes}: expected 0 (seed 003's fit) or more")
    footprints = int(footprints)
    if not 1 <= footprints or int(size) >> (footprints - 1) < 8:
        raise ValueError(
            f"footprints {footprints}: expected 1 or more, with R / 2^(F − 1) ≥ 8 (R = {size})"
        )
    models = MODELS if ptm else REQUIRED
    parameters = {
        "size": int(size),
        "samples": int(samples),
        "em_size": int(em_size),
        "levels": len(mip_sizes(int(em_size))),
        "smoothness": float(smoothness),
        "tie": tie,
        "lod_bias": float(lod_bias),
        "seed": int(seed),
        "bounces": TRACE_BOUNCES,
        "geometries": {"distant": "box", "local": "ellipsoid", "sphere": "infinity"},
        "lookup": "pixel centre, trilinear (bake/pem/lookups.py)",
        "lookups": lookups,
        "hull": "convex hull of all reflector parts",
        "environment": scene_obj.environment.checksum(),
    }
    if coupling:  # not in seed 003 (issue 31); absent: the independent bake of before
        parameters["coupling"] = coupling
        parameters["coupling_passes"] = int(coupling_passes)
    if exponent:  # issue 31 part 5 (seed 003 §7); absent: the mirror bake of before
        parameters["phong_exponent"] = exponent
    if rtol != SOLVE_RTOL:  # absent: the solve of before
        parameters["rtol"] = rtol
    if over_passes:  # not in seed 003 (bake/over.py); absent: the sequential fit of before
        parameters["over_passes"] = over_passes
    if footprints > 1:  # not in seed 003 (bake/models.py); absent: R's pixels alone
        parameters["footprints"] = footprints
    key = _bake_key(scene_path, scene_obj, {**parameters, "view_space": space.describe()})
    tasks = [
        ViewTask(
            str(scene_path.resolve()),
            i,
            float(c.azimuth),
            float(c.elevation),
            float(c.distance),
            tuple(float(t) for t in c.target),
            float(c.fov_y),
            int(size),
            int(samples),
            int(em_size),
            float(smoothness),
            int(seed),
            tie,
            float(lod_bias),
            lookups,
            gl_lookups if lookups == "gl" else None,
            models,
            coupling,
            phong_exponent=exponent,
            rtol=rtol,
            over_passes=over_passes,
            footprints=footprints,
        )
        for i, c in enumerate(space.cameras())
    ]
    return BakePlan(scene_obj, tracer, space, parameters, key, tasks, models, coupling)


def run_bake(
    scene: str | os.PathLike,
    views: ViewSpace | Callable[[OrbitCamera], ViewSpace],
    output: str | os.PathLike,
    size: int = 256,
    samples: int = 4,
    em_size: int = 64,
    smoothness: float = 1e-3,
    seed: int = 0,
    workers: int | None = None,
    on_view: Callable[[int, dict], None] | None = None,
    bar=None,
    scheduler: str | None = None,
    tie: float | None = None,
    connect_timeout: float | None = None,
    dask_workers: int = 2,
    lod_bias: float = LOD_BIAS,
    lookups: str = "auto",
    gl_lookups: type | None = None,
    ptm: bool = True,
    coupling: float = 0.0,
    coupling_passes: int = 2,
    only: list[int] | None = None,
    assemble: bool = True,
    probe: bool = True,
    phong_exponent: float | None = None,
    rtol: float | None = None,
    over_passes: int = 0,
    footprints: int = 1,
    zstd_level: int = 19,
) -> BakeReport:
    """Bake every view of ``views`` to ``output`` (a ``.pem``), resuming from its parts folder.

    Parameters
    ----------
    scene
        Shipped scene name or TOML scene file.
    views
        The parameter space, or a function of the scene's camera returning it
        (e.g. ``lambda c: arc_views(c, 100, 1.0)``).
    output
        The ``.pem`` path; its folder must exist.
    size, samples, em_size, smoothness, seed
        Trace resolution R, rays per pixel, finest cube face edge n (all levels
        n >> k down to 1 are inferred), λ, jitter seed.
    workers
        Processes of the local pool; 0 bakes in this process; None: one per core,
        at most one per view.
    on_view
        Called with (index, result) after each view's part is saved.
    bar
        A tqdm bar over views (``total`` and ``initial`` are set here).
    scheduler
        Bake on a Dask cluster instead of the local pool (``workers`` is then
        ignored): a scheduler address (``tcp://host:8786``), or ``"local"`` to start
        a ``LocalCluster`` (two worker processes, one thread each) and close it
        after. One future per unfinished view; parts are saved as they complete.
        An address that does not answer within ``connect_timeout`` seconds
        (default :data:`DASK_CONNECT_TIMEOUT`) raises a one-line ParameterError before
        anything is written.
    tie
        μ, the coarse-to-fine MIP ties (default: ``smoothness``).
    connect_timeout
        See ``scheduler``.
    dask_workers
        Worker processes of the ``"local"`` cluster.
    lod_bias
        Added to every lookup's level; stored as ``parameters["lod_bias"]`` for the
        playback to add too.
    lookups
        ``auto`` (GL when a context can be made, else CPU), ``gl`` or ``cpu``: where
        the per-pixel lookups A is built from come from (:class:`ViewTask`); stored
        as ``parameters["lookups"]``.
    gl_lookups
        The GL lookups' class (:class:`ViewTask`); None bakes with ``cpu`` lookups.
    ptm
        Also infer the PTM's per-view surface textures (issue 31; seed 003 §6,
        Figure 7). False: the three maps of seed 003 alone, as bakes before.
    coupling, coupling_passes
        γ of coupled inference and the coupled passes after the independent one
        (module docstring; not in seed 003). γ = 0: no coupled pass, and the
        parameters, parts and file of an uncoupled bake.
    only
        Bake just these views, in this order (the parts of the others are left as
        they are); None: every view.
    assemble
        Write ``output`` and remove the parts folder once every view is there.
        False: stop when the views are saved, the parts folder being the bake (a
        full-orbit PEM's views, :mod:`.orbit`); ``report.bake`` is then None.
    probe
        As :func:`plan_bake`.
    phong_exponent
        N > 0: trace glossy reflectors, their Phong lobe of exponent N sampled at
        each hit, stored as ``parameters["phong_exponent"]`` (issue 31 part 5; not in
        seed 003, whose §7 leaves glossy surfaces open). None or 0: mirrors, the
        parameters, parts and file of a bake made before the option.
    rtol
        The MIP solves' CG tolerance (:class:`ViewTask`); None: :func:`default_rtol`.
    over_passes
        The layered model's refits through its composite (:class:`ViewTask`, :mod:`.over`);
        0: seed 003's sequential fit.
    footprints
        The view's footprints in every solve (:class:`ViewTask`); 1: its own pixels.
    zstd_level
        The file's compression (:func:`~.pem_file.save_pem`): 19, small and slow (the
        100-view 256² bake: 13 min of its 34); 3 writes 5 % more in a 26th of the time
        (studies/pem-paper-scale/README.md).

    Returns
    -------
    BakeReport
    """
    start = time.perf_counter()
    output = check_output_path(output)
    plan = plan_bake(
        scene, views, size, samples, em_size, smoothness, seed, tie, lod_bias, lookups,
        gl_lookups, ptm, coupling, coupling_passes, probe, phong_exponent, rtol, over_passes,
        footprints,
    )  # fmt: skip
    scene_obj, space, parameters, key, tasks = (
        plan.scene,
        plan.space,
        plan.parameters,
        plan.key,
        plan.tasks,
    )
    models, coupling = plan.models, plan.coupling
    tracer = plan.tracer
    if only is not None:
        if coupling or assemble:
            raise ValueError("a subset of the views is baked uncoupled and not assembled")
        tasks = [tasks[i] for i in only]
    folder = parts_folder(output)
    report = BakeReport(bake=None, path=output)  # type: ignore[arg-type]
    keys = part_keys(int(em_size), models)
    passes = int(coupling_passes) if coupling else 0
    near = neighbours(space.describe())
    if bar is not None:
        bar.total = len(tasks) * (passes + 1)
    count = len(space.describe()["azimuths"])
    results = _run_pass(
        tasks, folder, key, keys, report, bar, on_view, workers, scheduler,
        connect_timeout, dask_workers, first=True,
    )  # fmt: skip
    for k in range(1, passes + 1):
        for colour in (0, 1):  # red-black: a colour's neighbours are all of the other
            half = [
                replace(
                    t, coupling_pass=k, anchors=neighbour_anchors(results, near[t.index], models)
                )
                for t in tasks
                if (t.index // count + t.index % count) % 2 == colour
            ]
            results.update(
                _run_pass(
                    half, folder, key, keys, report, bar, on_view, workers, scheduler,
                    connect_timeout, dask_workers, first=False,
                )
            )  # fmt: skip
    report.seconds = time.perf_counter() - start
    if not assemble:
        return report
    bake = _assemble(scene_obj, tracer, space, parameters, tasks, results, int(em_size), models)
    save_pem(output, bake, level=zstd_level)
    shutil.rmtree(folder, ignore_errors=True)
    report.bake = bake
    report.seconds = time.perf_counter() - start
    return report


def bake_tasks(
    tasks: list[ViewTask],
    output: str | os.PathLike,
    key: str,
    models: tuple[str, ...],
    workers: int | None = None,
    bar=None,
    on_view: Callable[[int, dict], None] | None = None,
) -> BakeReport:
    """Bake these work units into ``output``'s parts folder, nothing assembled.

    For work units made outside :func:`run_bake`: the full orbit's coupled views
    (orbit.py), each with its neighbours' anchors. Saved parts are reused, each view
    is handed to ``on_view`` as it ends.

    Parameters
    ----------
    tasks
        The work units (one bake's: ``key`` and ``models`` are its plan's).
    output
        The bake's ``.pem`` path (its parts folder holds the parts).
    key, models
        ``BakePlan.key`` and ``BakePlan.models``.
    workers, bar, on_view
        As :func:`run_bake`.
    """
    start = time.perf_counter()
    report = BakeReport(bake=None, path=Path(output))  # type: ignore[arg-type]
    if bar is not None:
        bar.total = len(tasks)
    em_size = tasks[0].em_size if tasks else 0
    _run_pass(
        tasks, parts_folder(output), key, part_keys(em_size, models), report, bar, on_view,
        workers, None, None, 2, first=True,
    )  # fmt: skip
    report.seconds = time.perf_counter() - start
    return report


def part_name(task: ViewTask) -> str:
    """``view-NNNNN.npz`` (independent pass), ``view-NNNNN-pass-K.npz`` (coupled pass K)."""
    suffix = f"-pass-{task.coupling_pass}" if task.coupling_pass else ""
    return f"view-{task.index:05d}{suffix}.npz"


def neighbour_anchors(
    results: dict[int, dict], near: list[int], models: tuple[str, ...]
) -> dict | None:
    """Per model and part, (mean, count) of the neighbours' maps, or None (no neighbour).

    The mean is (Σ_k 6 n_k², C) float64, levels concatenated as the solve's unknowns;
    a neighbour where the part is absent (NaN fit PSNR) does not count.
    """
    if not near:
        return None
    first = results[near[0]]
    out: dict[str, list] = {}
    for model in models:
        levels = sum(1 for name in first if name.startswith(f"{model}_") and name[-1].isdigit())
        out[model] = []
        for p in range(len(first[f"psnr_{model}"])):
            seen = [w for w in near if np.isfinite(results[w][f"psnr_{model}"][p])]
            flats = [
                np.concatenate(
                    [
                        np.asarray(results[w][f"{model}_{k}"][p], np.float64).reshape(
                            -1, results[w][f"{model}_{k}"].shape[-1]
                        )
                        for k in range(levels)
                    ]
                )
                for w in seen
            ]
            out[model].append((np.mean(flats, axis=0), len(seen)) if seen else None)
    return out


def _run_pass(
    tasks, folder, key, keys, report, bar, on_view, workers, scheduler, connect_timeout,
    dask_workers, first,
) -> dict[int, dict]:  # fmt: skip
    """One pass over every view: reuse saved parts, bake the rest, save each as it ends."""
    results: dict[int, dict] = {}
    for task in tasks:
        part = load_part(folder / part_name(task), key, task)
        if part is not None:
            results[task.index] = part
            if first:
                report.reused.append(task.index)
    todo = [t for t in tasks if t.index not in results]
    client = cluster = None
    if scheduler is not None and todo:  # before anything is written: it may not answer
        timeout = DASK_CONNECT_TIMEOUT if connect_timeout is None else float(connect_timeout)
        client, cluster = dask_client(scheduler, timeout, dask_workers)
    try:
        folder.mkdir(exist_ok=True)
        if bar is not None:
            done = bar.n if not first else 0
            bar.initial = bar.n = done + len(results)
            bar.refresh()
        count = min(os.cpu_count() or 1, len(todo)) if workers is None else int(workers)
        if client is not None:
            finished = _map_dask(todo, client)
        else:
            finished = _map_local(todo, max(0, min(count, len(todo))))
        for task, result in finished:
            _save_part(folder / part_name(task), key, task, result)
            results[task.index] = {k: result[k] for k in keys}
            if first:
                report.baked.append(task.index)
            report.trace_seconds.append(float(result["trace_seconds"]))
            report.infer_seconds.append(float(result["infer_seconds"]))
            if bar is not None:
                stage = f"pass {task.coupling_pass}, " if task.coupling_pass else ""
                bar.set_postfix_str(
                    f"{stage}view {task.index}: trace {float(result['trace_seconds']):.1f} s, "
                    f"infer {float(result['infer_seconds']):.1f} s"
                )
                bar.update(1)
            if on_view is not None:
                on_view(task.index, result)
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    return results


def _assemble(scene, tracer, space, parameters, tasks, results, em_size, models) -> PemBake:
    """The :class:`PemBake` of every view's part arrays, in view order."""
    box = distant_box(scene)
    ellipsoids, origins = [], []
    for p in range(len(tracer.part_names)):
        geometry, origin = local_ellipsoid(tracer, p)
        ellipsoids.append([geometry.centre, geometry.radii])
        origins.append(origin)
    order = [results[t.index] for t in tasks]
    levels = range(len(mip_sizes(em_size)))
    return PemBake(
        scene=scene.name,
        view_space=space.describe(),
        parts=list(tracer.part_names),
        parameters=parameters,
        maps={m: [np.stack([r[f"{m}_{k}"] for r in order]) for k in levels] for m in models},
        hull=reflector_hulls(scene),
        mesh_checks=[mesh_check(node) for node in scene.reflectors()],
        psnr={m: np.stack([r[f"psnr_{m}"] for r in order]) for m in models},
        playback_psnr={
            n: np.array([float(r[f"playback_{n}"]) for r in order])
            for n in PLAYBACK
            if f"playback_{n}" in order[0]
        },
        cameras=np.array([[t.azimuth, t.elevation] for t in tasks], dtype=np.float64),
        box=np.stack([box.lo, box.hi]),
        origins=np.array(origins, dtype=np.float64),
        ellipsoids=np.array(ellipsoids, dtype=np.float64),
    )
