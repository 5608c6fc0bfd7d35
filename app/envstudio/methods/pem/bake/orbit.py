"""A scene's full-orbit PEM: every view a user can orbit to, baked on demand (issue 31).

Seed 003 bakes a 100-view arc; a viewer's orbit camera reaches every azimuth and
elevations to ±89°. :class:`OrbitStore` is the PEM of the whole orbit
(:func:`~.views.orbit_views` at :data:`ORBIT_STEP`, the bake parameters of the
shipped arc bake) kept in the user cache: each view is a one-view ``.pem``
(:mod:`.pem_file`: half floats, zstd, checksummed), written atomically as soon as
it is baked and holding the key of the scene file, its environment's pixels, the
parameters and the view space. Views are baked when they are first needed,
nearest the camera first (:meth:`OrbitStore.bake`; in the viewer a background
process, methods/pem/orbit_job.py), and never assembled into one ``.pem``: at
5° spacing the orbit is 2664 views, so playback reads the few views it blends
from their files (methods/pem/resident.py). A cached view, ``shell.npz`` or resume
part that does not load (truncated, bit-flipped, empty, a folder, another orbit's) is
one note on stderr, discarded and baked again (as io/cache_entries.py's other caches).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import sys
import zipfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from envstudio.errors import InputFileError
from envstudio.io.atomic import atomic_path
from envstudio.io.cache_entries import discard
from envstudio.io.cache_folder import cache_folder
from envstudio.methods.pem.bake.bake import (
    BakeReport,
    bake_tasks,
    load_part,
    neighbour_anchors,
    neighbours,
    part_name,
    parts_folder,
    plan_bake,
    run_bake,
)
from envstudio.methods.pem.bake.hull import mesh_check, reflector_hulls
from envstudio.methods.pem.bake.infer import distant_box, local_ellipsoid
from envstudio.methods.pem.bake.pem_file import PemBake, load_pem, save_pem
from envstudio.methods.pem.bake.views import orbit_views
from envstudio.scene.camera import OrbitCamera

__all__ = [
    "ORBIT_BAKE",
    "ORBIT_CACHE_GB",
    "ORBIT_COUPLING",
    "ORBIT_STEP",
    "OrbitStore",
    "nearest_first",
    "orbit_cache_dir",
    "orbit_key",
    "prune_orbits",
]

#: (azimuth, elevation) spacing of the orbit's views in degrees, chosen by measurement:
#: the coarsest whose playback midway between samples is within 1 dB of the 2× denser
#: grid's (studies/pem-orbit/README.md).
ORBIT_STEP = (5.0, 5.0)

#: The orbit's bake parameters: those of the shipped arc bake (assets/pem/room.pem), the
#: three maps of seed 003 and the PTM's surface texture (Figure 7's comparison), the solve's
#: tolerance 10⁻⁴ (twice as fast as the default 10⁻⁶ at 64² EMs, and the same playback to
#: 0.08 dB at 24 random cameras; 10⁻³, faster still, lost up to 1.6 dB near the floor), and
#: the layered maps refitted through their composite twice (bake/over.py, not in seed 003:
#: without it the sphere at infinity leads at grazing views; studies/pem-orbit/README.md).
ORBIT_BAKE = {
    "size": 256,
    "samples": 4,
    "em_size": 64,
    "ptm": True,
    "rtol": 1e-4,
    "over_passes": 2,
}


#: The full orbit's coupling weight γ (pem's ``orbit_coupling``; not in seed 003): each
#: view inferred again drawn towards its four neighbours' maps. Part 4's trade on the arc
#: (studies/pem-bake/README.md); on the orbit the layered PEM then leads the sphere at infinity and
#: the static EM at all 24 random cameras, not 23, for 0.26 dB at the median
#: (studies/pem-orbit/README.md).
ORBIT_COUPLING = 0.1

#: The parameters that couple an orbit's views (without them: the orbit of before).
COUPLING_KEYS = ("coupling", "coupling_passes")

#: Views a coupled orbit bakes at a time (their neighbours first, uncoupled): nearest
#: first, a few at a time, so the first views about the camera come soon.
COUPLED_CHUNK = 4

#: zstd level of a view's file: fast (level 19, the bake file's, takes seconds a view).
VIEW_ZSTD_LEVEL = 3

#: Default cap of the orbits' cache, GB (``$ENVSTUDIO_ORBIT_CACHE_GB`` overrides): a whole
#: 5° orbit of ``room`` is about 1.3 GB of views above the floor (studies/pem-orbit/README.md).
ORBIT_CACHE_GB = 4.0


def _refuse(path: Path, reason: str) -> None:
    """A cache entry that does not load: one note, and it is discarded to be baked again."""
    print(f"envstudio: note: {reason}; discarded, baking again", file=sys.stderr)
    discard(path)


def _present(path: Path) -> bool:
    """Whether anything is at ``path``: a file, a folder, or a link (even a broken one)."""
    return path.is_symlink() or path.exists()


def orbit_cache_dir() -> Path:
    """``pem`` in envstudio's cache folder (:func:`~envstudio.io.cache_folder.cache_folder`)."""
    return cache_folder("pem")


def orbit_key(bake_key: str, models: tuple[str, ...]) -> str:
    """An orbit's identity: its bake's key (which does not name the models baked), and the
    PTM's surface textures where it has them (without: the identity of before them).

    Parameters
    ----------
    bake_key
        ``plan_bake(...).key`` of the orbit's views.
    models
        The maps each view holds (``plan.models``).
    """
    if "ptm" not in models:
        return bake_key
    return hashlib.sha256(f"{bake_key}+ptm".encode()).hexdigest()


def _last_used(folder: Path) -> float:
    """When an orbit folder was last opened or written (itself, or its views folder)."""
    times = [p.stat().st_mtime for p in (folder, folder / "views") if p.exists()]
    return max(times, default=0.0)


def _folder_bytes(folder: Path) -> int:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())


def prune_orbits(root: Path, keep: Path | tuple[Path, ...], cap_bytes: float) -> list[Path]:
    """Delete the least recently used orbit folders under ``root`` while they exceed the cap.

    Parameters
    ----------
    root
        The orbits' cache folder (:func:`orbit_cache_dir`).
    keep
        The orbit in use (and a coupled orbit's uncoupled one), never deleted (they alone
        may exceed the cap: their views are what the user is looking at).
    cap_bytes
        The cap on all ``orbit-*`` folders together, bytes.

    Returns
    -------
    list of Path
        The folders deleted, oldest first.
    """
    kept = {Path(keep)} if isinstance(keep, (str, Path)) else {Path(k) for k in keep}
    others = [p for p in Path(root).glob("orbit-*") if p.is_dir() and p not in kept]
    sizes = {p: _folder_bytes(p) for p in others}
    total = sum(sizes.values()) + sum(_folder_bytes(k) for k in kept if k.exists())
    deleted = []
    for folder in sorted(others, key=_last_used):
        if total <= cap_bytes:
            break
        shutil.rmtree(folder, ignore_errors=True)
        total -= sizes[folder]
        deleted.append(folder)
    return deleted


def orbit_cache_cap() -> float:
    """The orbits' cache cap in bytes: ``$ENVSTUDIO_ORBIT_CACHE_GB`` or :data:`ORBIT_CACHE_GB`.

    Raises
    ------
    InputFileError
        The variable is not a positive number.
    """
    text = os.environ.get("ENVSTUDIO_ORBIT_CACHE_GB", "")
    try:
        gigabytes = float(text) if text else ORBIT_CACHE_GB
    except ValueError:
        gigabytes = float("nan")
    if not (np.isfinite(gigabytes) and gigabytes > 0):
        raise InputFileError(f"ENVSTUDIO_ORBIT_CACHE_GB={text!r}: expected a size in GB > 0")
    return gigabytes * 1e9


def nearest_first(space: dict, camera: OrbitCamera, views: list[int] | None = None) -> list[int]:
    """Views ordered by the angle between their direction and the camera's, smallest first.

    Parameters
    ----------
    space
        ``ViewSpace.describe()``.
    camera
        The camera (its azimuth and elevation; the distance is not compared).
    views
        The view indices to order; None: all.

    Returns
    -------
    list of int
    """
    az = np.radians(np.asarray(space["azimuths"], dtype=np.float64))
    el = np.radians(np.asarray(space["elevations"], dtype=np.float64))
    e, a = np.meshgrid(el, az, indexing="ij")  # elevation-major, as the views
    directions = np.stack([np.cos(e) * np.sin(a), np.sin(e), np.cos(e) * np.cos(a)], -1)
    ca, ce = np.radians(camera.azimuth), np.radians(camera.elevation)
    d = np.array([np.cos(ce) * np.sin(ca), np.sin(ce), np.cos(ce) * np.cos(ca)])
    cosines = directions.reshape(-1, 3) @ d
    chosen = np.arange(len(cosines)) if views is None else np.asarray(views, dtype=np.int64)
    return [int(v) for v in chosen[np.argsort(-cosines[chosen], kind="stable")]]


class OrbitStore:
    """The full-orbit PEM of one scene in the user cache (module docstring).

    Parameters
    ----------
    scene
        Shipped scene name or TOML scene file.
    gl_lookups
        The GL lookups' class (methods/pem/lookups_gl.py), as :func:`~.bake.run_bake`;
        None bakes with CPU lookups (another orbit: the lookups are part of its key).
    step
        (azimuth, elevation) spacing, degrees.
    root
        The cache folder; default :func:`orbit_cache_dir`.
    parameters
        The bake's size, samples, em_size and ptm (default :data:`ORBIT_BAKE`). A
        ``coupling`` weight γ > 0 (with ``coupling_passes`` 1) stores coupled views: each
        inferred again, drawn towards its four neighbours' maps of the orbit without
        coupling (:attr:`independent`, baked first; :meth:`bake`).

    Attributes
    ----------
    folder : Path
        ``root/orbit-<scene>-<key>``: ``views/view-NNNNN.pem`` (each baked view as a
        one-view ``.pem``: half floats, zstd, checksummed, about a third of the
        bake's float32 part), ``shell.npz`` (the geometry playback needs) and, while a
        view is being baked, the bake's resume folder ``orbit.pem.parts/``.
    total : int
        Views of the orbit.
    independent : OrbitStore or None
        A coupled orbit's views without coupling, its anchors (the orbit of the same
        parameters without ``coupling``: the cache it has, shared); None uncoupled.
    """

    def __init__(
        self,
        scene: str,
        gl_lookups: type | None = None,
        step: tuple[float, float] = ORBIT_STEP,
        root: Path | None = None,
        parameters: dict | None = None,
    ):
        parameters = dict(ORBIT_BAKE if parameters is None else parameters)
        self.parameters = parameters
        self.scene_name = scene
        self.gl_lookups = gl_lookups
        self.step = step
        self.plan = plan_bake(
            scene,
            lambda camera: orbit_views(camera, *step),
            lookups="cpu" if gl_lookups is None else "gl",
            gl_lookups=gl_lookups,
            probe=False,
            **parameters,
        )
        self.space = self.plan.space.describe()
        self.total = len(self.plan.tasks)
        self.key = orbit_key(self.plan.key, self.plan.models)
        name = f"orbit-{self.plan.scene.name}-{self.key[:16]}"
        self.folder = (orbit_cache_dir() if root is None else Path(root)) / name
        self.output = self.folder / "orbit.pem"
        self.parts = parts_folder(self.output)
        self._shell: PemBake | None = None
        self._seen: dict[int, bool] = {}  # view → whether it saw a reflector (once baked)
        self._pruned = False  # the other orbits checked against the cache's cap
        self.independent: OrbitStore | None = None
        if self.plan.coupling:
            plain = {k: v for k, v in parameters.items() if k not in COUPLING_KEYS}
            self.independent = OrbitStore(scene, gl_lookups, step, root, plain)
            self.independent._pruned = True  # pruned with this orbit, which keeps it

    # -- what is baked -----------------------------------------------------------------------

    def view_path(self, view: int) -> Path:
        """``views/view-NNNNN.pem``: one baked view, a one-view bake file."""
        return self.folder / "views" / f"view-{view:05d}.pem"

    def done(self) -> set[int]:
        """Indices of the views whose file is there (not yet verified)."""
        names = (p.name for p in (self.folder / "views").glob("view-*.pem"))
        return {int(n[5:10]) for n in names if len(n) == 14 and n[5:10].isdigit()}

    def discard_unfinished(self) -> list[Path]:
        """Remove the temporary files of views whose writer was stopped mid-write.

        :func:`~envstudio.io.atomic.atomic_path` names them ``.view-NNNNN.<random>.pem``;
        a writer killed before its rename leaves one behind. Call it only when no
        writer of this orbit runs (the background job calls it once its child ended).

        Returns
        -------
        list of Path
            The files removed.
        """
        removed = sorted((self.folder / "views").glob(".view-*.pem"))
        for path in removed:
            path.unlink(missing_ok=True)
        return removed

    def _read(self, view: int) -> PemBake | None:
        """The one-view bake of ``view`` if it is there, intact and of this orbit.

        Whatever else is in its place (truncated, bit-flipped, empty, a folder, another
        orbit's view) is discarded with a one-line note, so that it is baked again.
        """
        path = self.view_path(view)
        if not _present(path):
            return None
        try:
            bake = load_pem(path)
        except InputFileError as error:
            _refuse(path, str(error))
            return None
        identity = (bake.parameters.get("orbit_key"), bake.parameters.get("orbit_view"))
        if identity != (self.key, view):
            _refuse(path, f"{path}: not view {view} of this orbit")
            return None
        return bake

    def sees_reflector(self, view: int) -> bool:
        """Whether the baked ``view`` saw a reflector part (a finite fit PSNR).

        Raises
        ------
        KeyError
            ``view`` is not baked (or its file is damaged).
        """
        if view not in self._seen and self.load(view) is None:
            raise KeyError(f"view {view} of {self.folder} is not baked")
        return self._seen[view]

    def load(self, view: int) -> dict[str, list[np.ndarray]] | None:
        """The maps of ``view``, or None where its file is missing, foreign or damaged.

        Returns
        -------
        dict or None
            Model → list over levels k of (P, 6, n_k, n_k, C) float32 (stored as half
            floats, as every ``.pem``).
        """
        bake = self._read(view)
        if bake is None:
            return None
        self._seen[view] = bool(np.isfinite(bake.psnr["distant"]).any())
        return {m: [level[0] for level in levels] for m, levels in bake.maps.items()}

    def _keep(self, view: int, result: dict) -> None:
        """Write a baked view as its one-view ``.pem`` and drop its resume part."""
        shell, levels = self.shell(), int(self.plan.parameters["levels"])
        bake = replace(
            shell,
            parameters={**shell.parameters, "orbit_key": self.key, "orbit_view": view},
            maps={m: [result[f"{m}_{k}"][None] for k in range(levels)] for m in self.plan.models},
            psnr={m: np.asarray(result[f"psnr_{m}"])[None] for m in self.plan.models},
            playback_psnr={
                n[9:]: np.asarray(result[n], np.float64).reshape(1)
                for n in result
                if n.startswith("playback_")
            },
            cameras=shell.cameras[view : view + 1],
            view_space={
                **{k: v for k, v in self.space.items() if k != "closed"},
                "kind": "arc",
                "azimuths": [float(shell.cameras[view, 0])],
                "elevations": [float(shell.cameras[view, 1])],
            },
        )
        self.view_path(view).parent.mkdir(parents=True, exist_ok=True)
        save_pem(self.view_path(view), bake, level=VIEW_ZSTD_LEVEL)
        (self.parts / part_name(self._task(view))).unlink(missing_ok=True)

    def _task(self, view: int):
        """The work unit whose result is the stored view (coupled: pass 1, no anchors yet)."""
        task = self.plan.tasks[view]
        return replace(task, coupling_pass=1) if self.plan.coupling else task

    def bake(
        self, views: list[int], workers: int | None = 1, bar=None, chunk: int = 0
    ) -> BakeReport:
        """Bake those of ``views`` not baked yet, in this order, each kept as it finishes.

        Parameters
        ----------
        views
            View indices.
        workers
            Processes (0: this process, whose GL context the lookups would share;
            the default bakes in one child process).
        bar
            A tqdm bar over the views.
        chunk
            A coupled orbit's views baked at a time (0: :data:`COUPLED_CHUNK`; more
            start fewer worker pools, fewer come sooner).

        The first call of a store marks its orbit as used and deletes the least recently
        used other orbits beyond the cache's cap (:func:`prune_orbits`,
        :func:`orbit_cache_cap`).
        """
        self.folder.mkdir(parents=True, exist_ok=True)
        if not self._pruned:
            os.utime(self.folder)
            in_use = (self.folder,) + (
                () if self.independent is None else (self.independent.folder,)
            )
            prune_orbits(self.folder.parent, in_use, orbit_cache_cap())
            self._pruned = True
        for view in self._resume_parts():  # baked, then interrupted before it was kept
            task = self._task(view)
            path = self.parts / part_name(task)
            part = load_part(path, self.plan.key, task)
            if part is None:
                _refuse(path, f"{path}: a resume part that does not load")
            else:
                self._keep(view, part)
        missing = [v for v in dict.fromkeys(views) if self._read(v) is None]
        if self.independent is not None:
            return self._bake_coupled(missing, workers, bar, chunk or COUPLED_CHUNK)
        return run_bake(
            self.scene_name,
            lambda camera: orbit_views(camera, *self.step),
            self.output,
            lookups="cpu" if self.gl_lookups is None else "gl",
            gl_lookups=self.gl_lookups,
            workers=workers,
            bar=bar,
            on_view=self._keep,
            only=missing,
            assemble=False,
            probe=False,
            **self.parameters,
        )

    def _bake_coupled(self, views: list[int], workers: int | None, bar, chunk: int) -> BakeReport:
        """Bake coupled ``views`` a few at a time, nearest first: first the views and their
        neighbours without coupling (:attr:`independent`), then each view again with the
        mean of its neighbours' maps as its anchor (one Jacobi pass of the coupled least
        squares of bake.py, from maps that do not depend on the order views are baked in)."""
        near = neighbours(self.space)
        models = self.plan.models
        report = BakeReport(bake=None, path=self.output)  # type: ignore[arg-type]
        if bar is not None:
            bar.total = len(views)
        for first in range(0, len(views), chunk):
            these = views[first : first + chunk]
            ring = list(dict.fromkeys(these + [n for v in these for n in near[v]]))
            self.independent.bake(ring, workers=workers)
            plain = {v: self.independent.result(v) for v in ring}
            tasks = [
                replace(self._task(v), anchors=neighbour_anchors(plain, near[v], models))
                for v in these
            ]
            done = bake_tasks(
                tasks, self.output, self.plan.key, models, workers, on_view=self._keep
            )
            report.baked += done.baked
            report.trace_seconds += done.trace_seconds
            report.infer_seconds += done.infer_seconds
            if bar is not None:
                bar.update(len(these))
        return report

    def result(self, view: int) -> dict[str, np.ndarray]:
        """A baked view's maps and fit PSNRs as the bake's work units give them.

        Returns
        -------
        dict
            ``{model}_{k}`` (P, 6, n_k, n_k, C) float32 and ``psnr_{model}`` (P,).

        Raises
        ------
        KeyError
            ``view`` is not baked (or its file is damaged).
        """
        bake = self._read(view)
        if bake is None:
            raise KeyError(f"view {view} of {self.folder} is not baked")
        out = {
            f"{m}_{k}": np.asarray(level[0], np.float32)
            for m, levels in bake.maps.items()
            for k, level in enumerate(levels)
        }
        out.update({f"psnr_{m}": np.asarray(bake.psnr[m][0], np.float64) for m in bake.maps})
        return out

    def _resume_parts(self) -> list[int]:
        names = (p.name for p in self.parts.glob("view-*.npz")) if self.parts.is_dir() else ()
        suffix = "-pass-1.npz" if self.plan.coupling else ".npz"
        return [int(n[5:10]) for n in names if n == f"view-{n[5:10]}{suffix}" and n[5:10].isdigit()]

    # -- what playback needs ---------------------------------------------------------------------

    def shell(self) -> PemBake:
        """The orbit as a bake without views: its geometry, parameters and view space.

        ``maps`` holds one zero view (the playback's slots replace it), ``cameras``
        every view's angles. Computed once (the reflectors' ellipsoids need the
        tracer) and kept in ``shell.npz``.
        """
        if self._shell is None:
            self._shell = self._read_shell() or self._write_shell()
        return self._shell

    def _empty_maps(self) -> dict[str, list[np.ndarray]]:
        n, parts = int(self.parameters["em_size"]), len(self.plan.tracer.part_names)
        channels = {"distant": 3, "local": 4, "sphere": 3, "ptm": 3}
        levels = int(self.plan.parameters["levels"])
        shapes = [(1, parts, 6, n >> k, n >> k) for k in range(levels)]
        return {
            m: [np.zeros((*shape, channels[m]), np.float32) for shape in shapes]
            for m in self.plan.models
        }

    def _shell_of(self, geometry: dict) -> PemBake:
        cameras = np.array([[t.azimuth, t.elevation] for t in self.plan.tasks], np.float64)
        return PemBake(
            scene=self.plan.scene.name,
            view_space=self.space,
            parts=list(self.plan.tracer.part_names),
            parameters=self.plan.parameters,
            maps=self._empty_maps(),
            hull=[np.asarray(h, bool) for h in geometry["hull"]],
            mesh_checks=[mesh_check(node) for node in self.plan.scene.reflectors()],
            psnr={},
            playback_psnr={},
            cameras=cameras,
            box=np.asarray(geometry["box"], np.float64),
            origins=np.asarray(geometry["origins"], np.float64),
            ellipsoids=np.asarray(geometry["ellipsoids"], np.float64),
        )

    def _read_shell(self) -> PemBake | None:
        """``shell.npz`` if it is there, intact and of this orbit; anything else in its
        place is discarded with a one-line note (and computed again)."""
        path = self.folder / "shell.npz"
        if not _present(path):
            return None
        parts = len(self.plan.tracer.part_names)
        try:
            with np.load(path, allow_pickle=False) as data:
                key = str(data["key"])
                geometry = {
                    "box": data["box"],
                    "origins": data["origins"],
                    "ellipsoids": data["ellipsoids"],
                    "hull": [data[f"hull_{p}"] for p in range(parts)],
                }
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            _refuse(path, f"{path}: not a readable orbit shell ({reason})")
            return None
        if key != self.key:
            _refuse(path, f"{path}: the shell of another orbit")
            return None
        return self._shell_of(geometry)

    def _write_shell(self) -> PemBake:
        tracer, scene = self.plan.tracer, self.plan.scene
        box = distant_box(scene)
        local = [local_ellipsoid(tracer, p) for p in range(len(tracer.part_names))]
        geometry = {
            "box": np.stack([box.lo, box.hi]),
            "origins": np.array([o for _, o in local], np.float64),
            "ellipsoids": np.array([[g.centre, g.radii] for g, _ in local], np.float64),
            "hull": reflector_hulls(scene),
        }
        self.folder.mkdir(parents=True, exist_ok=True)
        hulls = {f"hull_{p}": np.asarray(h, bool) for p, h in enumerate(geometry["hull"])}
        with atomic_path(self.folder / "shell.npz") as tmp:
            with open(tmp, "wb") as f:
                np.savez(
                    f,
                    key=np.array(self.key),
                    box=geometry["box"],
                    origins=geometry["origins"],
                    ellipsoids=geometry["ellipsoids"],
                    **hulls,
                )
        return self._shell_of(geometry)

    def describe(self) -> str:
        """One line: the orbit's grid and where it is kept."""
        el = self.space["elevations"]
        return (
            f"{self.total} views ({len(self.space['azimuths'])} azimuths × {len(el)} elevations "
            f"{el[0]:g}°…{el[-1]:g}°, {self.step[0]:g}° × {self.step[1]:g}°) in {self.folder}"
        )
