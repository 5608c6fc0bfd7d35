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
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from envstudio.bake.pem.infer import distant_box, infer_distant, local_ellipsoid
from envstudio.bake.pem.pem_file import FORMAT, VERSION, PemBake, save_pem
from envstudio.bake.pem.trace import TRACE_BOUNCES, SceneTracer
from envstudio.bake.pem.views import ViewSpace
from envstudio.io.atomic import atomic_path, check_output_path
from envstudio.io.scene_file import load_scene, resolve_scene
from envstudio.scene.camera import OrbitCamera

__all__ = ["BakeReport", "ViewTask", "bake_view", "parts_folder", "run_bake"]

_PART_KEYS = ("distant", "seen", "psnr", "iterations")


@dataclass(frozen=True)
class ViewTask:
    """One work unit: trace one view and infer each part's distant EM.

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
        λ of :func:`~envstudio.bake.pem.infer.infer_em`.
    seed : int
        Jitter seed; the view traces with ``seed + index``.
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

    def camera(self) -> OrbitCamera:
        """The view's camera."""
        return OrbitCamera(
            azimuth=self.azimuth,
            elevation=self.elevation,
            distance=self.distance,
            target=np.array(self.target, dtype=np.float64),
            fov_y=self.fov_y,
        )


_TRACERS: dict[str, tuple] = {}


def _tracer(scene_path: str):
    if scene_path not in _TRACERS:
        scene = load_scene(scene_path)
        _TRACERS[scene_path] = (scene, SceneTracer(scene))
    return _TRACERS[scene_path]


def bake_view(task: ViewTask) -> dict[str, np.ndarray]:
    """Trace one view and infer every part's distant box EM (seed 003 §4, "EM Inference").

    Parameters
    ----------
    task
        The work unit.

    Returns
    -------
    dict
        ``distant`` (P, 6, n, n, 3) float32, ``seen`` (P, 6, n, n) uint8, ``psnr``
        (P,) float64 (NaN for a part not in the view, whose map is 0),
        ``iterations`` (P, 3) int32, and ``trace_seconds``, ``infer_seconds``
        (0-d float64).
    """
    scene, tracer = _tracer(task.scene)
    view = tracer.trace(task.camera(), task.size, task.samples, task.seed + task.index)
    start = time.perf_counter()
    n, parts = task.em_size, len(tracer.part_names)
    out = {
        "distant": np.zeros((parts, 6, n, n, 3), np.float32),
        "seen": np.zeros((parts, 6, n, n), np.uint8),
        "psnr": np.full(parts, np.nan),
        "iterations": np.zeros((parts, 3), np.int32),
    }
    for p in range(parts):
        if not np.any(view.coverage[p] > 0):
            continue
        em = infer_distant(scene, tracer, view, p, size=n, smoothness=task.smoothness)
        out["distant"][p] = em.em
        out["seen"][p] = em.seen
        out["psnr"][p] = em.psnr
        out["iterations"][p] = em.iterations
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
    for name in _PART_KEYS:
        digest.update(np.ascontiguousarray(arrays[name]).tobytes())
    return digest.hexdigest()


def _part_header(key: str, task: ViewTask) -> dict:
    return {"key": key, "task": asdict(task)}


def _save_part(path: Path, key: str, task: ViewTask, result: dict) -> None:
    arrays = {k: np.ascontiguousarray(result[k]) for k in _PART_KEYS}
    header = _part_header(key, task)
    meta = {"header": header, "checksum": _part_checksum(arrays, header)}
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            np.savez(f, meta=np.array(json.dumps(meta, sort_keys=True)), **arrays)


def _load_part(path: Path, key: str, task: ViewTask) -> dict | None:
    """The part's arrays if it is readable, of this bake and view, and intact; else None."""
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            arrays = {k: np.asarray(data[k]) for k in _PART_KEYS}
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


def _map_dask(tasks, scheduler: str):
    """Yield (task, result) as views finish on a Dask cluster (``"local"``: a LocalCluster)."""
    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError:  # pragma: no cover - the cluster extra is in the lock
        raise ValueError(
            "a Dask bake needs dask and distributed: pip install 'envmap-studio[cluster]'"
        ) from None
    cluster = None
    if scheduler == "local":
        # worker processes start with spawn (distributed's default): no fork after Embree
        cluster = LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)
    else:
        client = Client(scheduler)
    try:
        futures = {client.submit(bake_view, t, pure=False): t for t in tasks}
        try:
            for future in as_completed(futures):
                yield futures[future], future.result()
        except BaseException:
            client.cancel(list(futures))
            raise
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


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
        Trace resolution R, rays per pixel, cube face edge n, λ, jitter seed.
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

    Returns
    -------
    BakeReport
    """
    start = time.perf_counter()
    output = check_output_path(output)
    scene_path = resolve_scene(scene)
    scene_obj = load_scene(scene_path)
    tracer = SceneTracer(scene_obj)  # raises ValueError for a scene without a reflector
    space = views if isinstance(views, ViewSpace) else views(scene_obj.camera)
    parameters = {
        "size": int(size),
        "samples": int(samples),
        "em_size": int(em_size),
        "smoothness": float(smoothness),
        "seed": int(seed),
        "bounces": TRACE_BOUNCES,
        "layer": "distant",
        "geometry": "box",
    }
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
        )
        for i, c in enumerate(space.cameras())
    ]
    folder = parts_folder(output)
    folder.mkdir(exist_ok=True)
    results: dict[int, dict] = {}
    report = BakeReport(bake=None, path=output)  # type: ignore[arg-type]
    for task in tasks:
        part = _load_part(folder / f"view-{task.index:05d}.npz", key, task)
        if part is not None:
            results[task.index] = part
            report.reused.append(task.index)
    todo = [t for t in tasks if t.index not in results]
    if bar is not None:
        bar.total, bar.initial, bar.n = len(tasks), len(results), len(results)
        bar.refresh()
    count = min(os.cpu_count() or 1, len(todo)) if workers is None else int(workers)
    if scheduler is not None and todo:
        finished = _map_dask(todo, scheduler)
    else:
        finished = _map_local(todo, max(0, min(count, len(todo))))
    for task, result in finished:
        _save_part(folder / f"view-{task.index:05d}.npz", key, task, result)
        results[task.index] = {k: result[k] for k in _PART_KEYS}
        report.baked.append(task.index)
        report.trace_seconds.append(float(result["trace_seconds"]))
        report.infer_seconds.append(float(result["infer_seconds"]))
        if bar is not None:
            bar.set_postfix_str(
                f"view {task.index}: trace {float(result['trace_seconds']):.1f} s, "
                f"infer {float(result['infer_seconds']):.1f} s"
            )
            bar.update(1)
        if on_view is not None:
            on_view(task.index, result)
    box = distant_box(scene_obj)
    ellipsoids, origins = [], []
    for p in range(len(tracer.part_names)):
        geometry, origin = local_ellipsoid(tracer, p)
        ellipsoids.append([geometry.centre, geometry.radii])
        origins.append(origin)
    order = [results[t.index] for t in tasks]
    bake = PemBake(
        scene=scene_obj.name,
        view_space=space.describe(),
        parts=list(tracer.part_names),
        parameters=parameters,
        distant=np.stack([r["distant"] for r in order]),
        seen=np.stack([r["seen"] for r in order]),
        psnr=np.stack([r["psnr"] for r in order]),
        iterations=np.stack([r["iterations"] for r in order]),
        cameras=np.array([[t.azimuth, t.elevation] for t in tasks], dtype=np.float64),
        box=np.stack([box.lo, box.hi]),
        origins=np.array(origins, dtype=np.float64),
        ellipsoids=np.array(ellipsoids, dtype=np.float64),
    )
    save_pem(output, bake)
    shutil.rmtree(folder, ignore_errors=True)
    report.bake = bake
    report.seconds = time.perf_counter() - start
    return report
