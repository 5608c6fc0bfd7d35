"""A scene's full orbit on show (issue 31, ``coverage``): its views baked as they are blended.

Every view the orbit camera reaches (methods/pem/bake/orbit.py) is baked on first
use into the user cache, nearest the camera first: headless, the views a frame
blends are baked before it is drawn (a progress bar on a terminal); in the window,
by a background process (methods/pem/orbit_job.py) while the static EM shows until
the views around the camera are ready. Only the views being blended are on the
GPU (methods/pem/resident.py).
"""

from __future__ import annotations

import sys

import moderngl
import numpy as np

from envstudio.methods.pem.bake.orbit import ORBIT_BAKE, ORBIT_COUPLING, OrbitStore
from envstudio.methods.pem.blending import ViewBlend, camera_angles, ptm_blend
from envstudio.methods.pem.lookups_gl import GlLookups
from envstudio.methods.pem.orbit_job import FAILED_RETRY_S, OrbitBakeJob
from envstudio.methods.pem.resident import ResidentViews
from envstudio.methods.pem.verify import check_bake_for_scene
from envstudio.plugin import FrameInputs, GpuScene, InputFileError, ParameterValues
from envstudio.scene.camera import OrbitCamera

__all__ = ["OrbitPlayback", "full_orbit_store", "orbit_playback_key"]

#: The method's parameters that pick a full orbit's cache.
_CACHE_PARAMETERS = ("orbit_step", "orbit_em_size", "orbit_fit", "orbit_coupling")


def full_orbit_store(
    source: str,
    step: float,
    em_size: int,
    fit: str = "refit",
    coupling: float = ORBIT_COUPLING,
) -> OrbitStore:
    """The full orbit of a scene file, ``step`` degrees apart on both axes, with
    ``em_size``² maps (its views baked with the GL lookups), its layered maps fitted by
    ``fit`` (``refit`` or ``seed003``: no refit through the composite), its views
    coupled with weight ``coupling`` (0: each alone)."""
    parameters = {**ORBIT_BAKE, "em_size": int(em_size)}
    if fit == "seed003":
        parameters["over_passes"] = 0
    if coupling:
        parameters.update(coupling=float(coupling), coupling_passes=1)
    return OrbitStore(source, GlLookups, (step, step), parameters=parameters)


def orbit_playback_key(scene: GpuScene, values: ParameterValues) -> tuple:
    """What a loaded orbit is valid for: the scene file, the scene, its environment and
    meshes (either may be replaced in place), the grid (its ``orbit_*`` ``values``)."""
    meshes = tuple(id(node.mesh) for node in scene.reflectors())
    chosen = tuple(str(values[k]) for k in _CACHE_PARAMETERS)
    where = (scene.scene.source, id(scene), id(scene.scene.environment))
    return ("orbit", *where, meshes, chosen)


class OrbitPlayback:
    """A full orbit's geometry on the GPU, its views baked and moved in as they are blended.

    Parameters
    ----------
    ctx
        The context.
    store
        The scene file's full orbit (:func:`full_orbit_store`).
    scene
        The scene on show.
    key
        What the method keeps it loaded for (:func:`orbit_playback_key`).

    Raises
    ------
    InputFileError
        The scene's environment was replaced since it was read (the orbit bakes the
        scene file's), or the orbit's geometry does not fit the scene's reflectors.
    """

    def __init__(self, ctx: moderngl.Context, store: OrbitStore, scene: GpuScene, key: tuple):
        if store.plan.scene.environment.checksum() != scene.scene.environment.checksum():
            raise InputFileError(
                f"scene {scene.scene.name}: its environment was replaced; the full orbit bakes "
                "the scene file's (set coverage=file and bake one with `envstudio bake pem`)"
            )
        shell = store.shell()
        check_bake_for_scene(shell, scene.scene, store.folder)
        self.textures = ResidentViews(ctx, shell)
        self.key = key
        self.path = store.folder
        #: The orbit's geometry and parameters; its views' maps are in :attr:`orbit`.
        self.bake = shell
        self.orbit = store
        #: The reflectors' 4 x 4 model matrices it is played for, one per part.
        self.models = [np.array(n.model, dtype=np.float64) for n in scene.reflectors()]
        #: The window's background bake of the orbit (None: headless, or not yet asked).
        self.job: OrbitBakeJob | None = None

    def view_maps(self, view: int) -> dict[str, list[np.ndarray]] | None:
        """One view's maps, model → levels of (P, 6, n_k, n_k, C) (None: not baked yet)."""
        return self.orbit.load(view)

    def place(
        self, frame: FrameInputs, blend: ViewBlend, ptm: bool, budgeted: bool
    ) -> tuple[ViewBlend, list[int]] | None:
        """The blend over the views that see the reflector, and their atlas slots.

        The views blended with a weight are baked where needed: ``budgeted`` false
        (headless), now; else (the window) the background bake is asked for them
        (and the rest of the orbit after), and None is returned until they are
        there. A view that saw no reflector (a camera under the floor) leaves the
        blend, the others' weights scaled up to sum to 1 (its maps are empty, not
        the scene). ``ptm``: ``blend`` is the PTM's window (weights of either sign),
        every view of it is baked and the polynomial is fitted again to those that
        saw the reflector.

        Raises
        ------
        InputFileError
            Headless, the views did not bake.
        """
        orbit = self.orbit
        pairs = zip(blend.views, blend.weights, strict=True)
        weighted = list(blend.views) if ptm else [v for v, w in pairs if w > 0.0]
        weighted = list(dict.fromkeys(weighted or blend.views[:1]))
        slots = self.textures.slots(weighted, orbit.load)
        if not budgeted:
            if slots is None:
                self._bake_now(weighted)
                slots = self.textures.slots(weighted, orbit.load)
            if slots is None:
                raise InputFileError(f"{orbit.parts}: views {weighted} did not bake")
        else:
            if self.job is None:
                self.job = OrbitBakeJob(orbit, frame.scene.scene.source)
            target = self.bake.view_space["target"]
            azimuth, elevation = camera_angles(frame.camera_position, target)
            self.job.request(OrbitCamera(azimuth=azimuth, elevation=elevation), weighted)
            if slots is None:
                return None
        where = dict(zip(weighted, slots, strict=True))
        if ptm:
            space, eye = self.bake.view_space, frame.camera_position
            blend = ptm_blend(space, eye, usable=orbit.sees_reflector)
            return blend, [where[v] for v in blend.views]
        pairs = [(v, w) for v, w in zip(blend.views, blend.weights, strict=True) if w > 0.0]
        seen = [(v, w) for v, w in pairs if orbit.sees_reflector(v)]
        if seen and len(seen) < len(pairs):
            total = sum(w for _, w in seen)
            blend = ViewBlend(
                tuple(v for v, _ in seen), tuple(w / total for _, w in seen), blend.position
            )
        return blend, [where.get(v, slots[0]) for v in blend.views]

    def _bake_now(self, views: list[int]) -> None:
        """Bake ``views`` before the frame (headless), a bar on a terminal."""
        from tqdm import tqdm

        orbit = self.orbit
        with tqdm(
            unit="view", desc="pem orbit", leave=False, disable=not sys.stderr.isatty()
        ) as bar:
            # a child process for the GL lookups: this one holds the frame's context
            orbit.bake(views, workers=0 if orbit.gl_lookups is None else 1, bar=bar)

    def progress(self) -> float | None:
        """The fraction of views baked while the background bake runs (None otherwise)."""
        if self.job is None or not self.job.running:
            return None
        return len(self.job.done()) / self.orbit.total

    def progress_line(self, waiting: bool) -> str:
        """The status line: views baked, time left, and what is on show (``waiting``: the
        static EM, the views about the camera not baked yet)."""
        orbit, job = self.orbit, self.job
        done = len(job.done() if job is not None else orbit.done())
        line = f"full orbit: {done} of {orbit.total} views baked"
        left = None if job is None else job.seconds_left()
        if job is not None and job.failure:
            line += f" ({job.failure}; retried every {FAILED_RETRY_S:.0f} s)"
        if job is not None and job.running:
            line += " (baking nearest the camera first" + (
                f", about {left / 60:.0f} min left)" if left is not None else ")"
            )
        if waiting:
            return line + "; the static EM shows until the views around the camera are baked"
        return line + f"; {self.textures.megabytes:.0f} MB resident"

    def bench_notes(self, blended: int) -> dict:
        """Views baked and resident, texture MB, the last view's upload ms and ``blended``,
        the views the last frame blended."""
        textures = self.textures
        return {
            "bake": f"full orbit, {self.orbit.describe()}",
            "views_baked": len(self.orbit.done()),
            "views_resident": len(textures.resident),
            "texture_mb": round(textures.megabytes, 2),
            "view_switch_upload_ms": round(textures.upload_ms, 2),
            "views_blended": blended,
        }

    def release(self) -> None:
        """Stop the background bake and free the textures."""
        if self.job is not None:
            self.job.stop()
        self.textures.release()
