"""Method ``pem``: parameterized environment map playback (seed 003 §4–6).

A bake (``envstudio bake pem``: per view and reflector part, the inferred
distant box map, the local ellipsoid map as premultiplied RGBA, and a single
sphere-at-infinity map, every MIP level) is drawn by shaders/pem/pem.glsl:
per-fragment texgen against the box and the part's ellipsoid, the layered
composite with Schlick Fresnel and the SH diffuse layer, blended over the
nearest views of the parameter space (methods/pem/blending.py). The EM model
switch also offers the sphere at infinity and the scene's static EM (seed 003
Figures 1 and 6) and the PTM of Figure 7 (issue 31: the bake's per-view surface
textures, a per-texel polynomial in the view parameters, methods/pem/blending.py).
Without a bake for the scene the method shows the static EM and says how to bake
one.

The full orbit (issue 31, ``coverage``): a scene that ships a bake plays the PEM
of every view the orbit camera reaches (methods/pem/bake/orbit.py), baked on first
use into the user cache, nearest the camera first: headless, the views a frame
blends are baked before it is drawn (a progress bar on a terminal); in the window,
by a background process (methods/pem/orbit_job.py) while the static EM shows until
the views around the camera are ready, with the Method panel's progress bar. Only
the views being blended are on the GPU (methods/pem/resident.py).
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import moderngl
import numpy as np

from envstudio.core.cubemap import faces_to_cross
from envstudio.methods.pem.bake.orbit import ORBIT_BAKE, ORBIT_COUPLING, ORBIT_STEP, OrbitStore
from envstudio.methods.pem.bake.pem_file import PemBake, load_pem
from envstudio.methods.pem.blending import ViewBlend, camera_angles, ptm_blend, view_blend
from envstudio.methods.pem.gpu import ATLASES, MODELS, TEXGENS, PemTextures, texgen_defines
from envstudio.methods.pem.lookups_gl import GlLookups
from envstudio.methods.pem.orbit_job import FAILED_RETRY_S, OrbitBakeJob
from envstudio.methods.pem.resident import SLOTS, ResidentViews
from envstudio.methods.pem.verify import check_bake_for_scene
from envstudio.plugin import (
    FrameInputs,
    GpuScene,
    InputFileError,
    Method,
    Parameter,
    ReportExtra,
    fresnel_parameter,
    kd_parameter,
    set_uniform,
    to_ldr,
    upright,
)
from envstudio.resources import asset_root
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.graph import Scene

__all__ = ["PemMethod", "shipped_bake"]


def _file_view(bake: PemBake, view: int) -> dict[str, list[np.ndarray]]:
    """One view's maps of a bake file: model → levels of (P, 6, n_k, n_k, C)."""
    return {m: [level[view] for level in levels] for m, levels in bake.maps.items()}


def shipped_bake(scene_name: str) -> Path:
    """Where a scene's shipped bake lives: ``assets/pem/<scene>.pem``."""
    return asset_root() / "pem" / f"{scene_name}.pem"


@dataclass
class _Loaded:
    """The bake on show and what it was loaded for."""

    key: tuple
    path: Path
    bake: PemBake  # a full orbit's: its geometry, the views are in ``orbit``
    textures: PemTextures | ResidentViews
    models: list = field(default_factory=list)  # the reflectors' model matrices it was baked for
    orbit: OrbitStore | None = None
    job: OrbitBakeJob | None = None  # the window's background bake of the orbit


class PemMethod(Method):
    """Layered PEM playback with view blending (seed 003 §4, "run-time")."""

    name = "pem"
    paper = "Hakura, Snyder, Lengyel 2001 (seed 003)"
    title = "PEM (Hakura–Snyder–Lengyel)"
    summary = (
        "Per-view environment maps inferred from ray traces (box + ellipsoid layers), "
        "blended across the nearest baked views."
    )
    panel_figure = "Inferred maps of the nearest view (seed 003 Figure 5)"
    parameters = (
        Parameter(
            "pem",
            "path",
            "",
            help="The .pem bake to play; empty: the scene's shipped bake (assets/pem/<scene>.pem).",
            choices=(".pem",),
        ),
        Parameter(
            "coverage",
            "choice",
            "auto",
            help="orbit: every view the orbit camera reaches, baked on first use into the "
            "user cache (nearest the camera first; in the background in the window); file: "
            "the views of the .pem; auto: the orbit for a scene that ships a bake and no "
            "pem is named, else the file.",
            choices=("auto", "orbit", "file"),
        ),
        Parameter(
            "orbit_step",
            "choice",
            f"{ORBIT_STEP[0]:g}",
            help="Degrees between the full orbit's views in azimuth and elevation (each "
            "spacing its own cache; docs/pem/orbit.md: the finer, the closer midway, and the "
            "more views to bake).",
            choices=("20", "10", "5"),
        ),
        Parameter(
            "orbit_em_size",
            "choice",
            f"{ORBIT_BAKE['em_size']}",
            help="Cube face edge of the full orbit's maps (each size its own cache; "
            "docs/pem/orbit.md: 128 fits the teapot's self-reflections at grazing views, at "
            "four times the disk and the bake time).",
            choices=("64", "128"),
        ),
        Parameter(
            "orbit_fit",
            "choice",
            "refit",
            help="How the full orbit's layered maps are fitted (each its own cache): seed003, "
            "the paper's sequence (distant layer to its segment, then the local RGBA through "
            "the over); refit, then the distant and local colour refitted through the "
            "composite (not in the paper; docs/pem/orbit.md: the layered PEM then leads the "
            "sphere at grazing views).",
            choices=("refit", "seed003"),
        ),
        Parameter(
            "orbit_coupling",
            "choice",
            f"{ORBIT_COUPLING:g}",
            help="Coupling weight γ of the full orbit's views (each its own cache; not in the "
            "paper): 0, each view inferred alone; 0.1, each inferred again drawn towards its "
            "four neighbours' maps, which blend with less ghosting: the layered PEM then leads "
            "everywhere measured (docs/pem/orbit.md).",
            choices=("0", "0.1"),
        ),
        Parameter(
            "em_model",
            "choice",
            "layered",
            help="EM model: layered box + ellipsoid, one sphere at infinity, the static EM, or "
            "the PTM (surface textures, a polynomial in the view: seed 003 Figure 7).",
            choices=MODELS,
        ),
        Parameter(
            "texgen",
            "choice",
            "fragment",
            help="Reflection lookups per fragment, or per vertex as the paper (interpolated).",
            choices=TEXGENS,
            rebuild=True,
        ),
        Parameter(
            "lod_scale",
            "choice",
            "screen",
            help="MIP level from this image's pixel footprint (screen, as the hardware), or as "
            "the bake's resolution saw it (bake: the levels the solve fitted, at any size).",
            choices=("screen", "bake"),
        ),
        Parameter("blend", "bool", True, help="Blend the nearest 2 (arc) or 4 (grid) views."),
        Parameter("snap", "bool", False, help="Put the camera on the baked path at `path`."),
        Parameter("play", "bool", False, help="Move the camera along the path (snaps it)."),
        Parameter("path", "float", 0.5, 0.0, 1.0, "", "Position along the path's azimuths."),
        Parameter(
            "path_elevation", "float", 0.5, 0.0, 1.0, "", "Position along a grid's elevations."
        ),
        Parameter("play_speed", "float", 0.1, 0.01, 1.0, "1/s", "Path fraction per second."),
        Parameter("distant", "bool", True, help="Distant layer (the box map)."),
        Parameter("local", "bool", True, help="Local layer (the ellipsoid map, RGBA over)."),
        Parameter("fresnel_layer", "bool", True, help="Fresnel modulation of the reflection."),
        Parameter("diffuse", "bool", True, help="Diffuse layer (1 − F) k_d/π E_sh9(n)."),
        Parameter("hull", "bool", True, help="Convex-hull triangles use the distant map only."),
        fresnel_parameter(1.0, "Schlick f_λ of the Fresnel layer, per RGB channel."),
        kd_parameter(0.0, "Diffuse albedo of the diffuse layer, per RGB channel."),
    )

    @staticmethod
    def orbit_store(
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

    def __init__(self, ctx: moderngl.Context, programs):
        super().__init__(ctx, programs)
        self._loaded: _Loaded | None = None
        self._missing: str = ""
        self._other_environment = ""  # the bake's recorded environment is not the scene's
        self._dummy: dict[str, moderngl.Texture] = {}
        self._thumbnails: list[moderngl.Texture] = []
        self._last_play: float | None = None
        self._moved = False
        self._shown_pem = ""  # the ``pem`` value of what is on show (a failed load returns to it)
        self.last_blend: ViewBlend | None = None
        self._drawn_static = False  # a full orbit's views about the camera were not there
        self._orbit_refused: tuple[tuple, str] | None = None  # (its key, why): not retried

    # -- loading ---------------------------------------------------------------------

    def _requested(self, scene: GpuScene) -> tuple[Path, bool]:
        """The bake file asked for and whether it was named explicitly."""
        named = str(self.values["pem"]).strip()
        if named:
            return Path(named).expanduser(), True
        return shipped_bake(scene.scene.name), False

    def _key(self, scene: GpuScene) -> tuple:
        """What a loaded bake is valid for: the file asked for, the scene, its meshes, the
        coverage asked for."""
        path, _ = self._requested(scene)
        meshes = tuple(id(node.mesh) for node in scene.reflectors())
        where = str(path.resolve()) if path.exists() else str(path)
        return (where, id(scene), meshes, str(self.values["coverage"]))

    def prepare(self, scene: GpuScene) -> None:
        """Load and verify the bake the ``pem`` parameter names (kept while unchanged).

        Raises
        ------
        InputFileError
            The file is missing, not a valid ``.pem``, or baked for another scene
            or mesh; what was shown before stays (a bake, or the static EM), and
            ``pem`` is set back to its value.
        """
        path, named = self._requested(scene)
        key = self._key(scene)
        if self._loaded is not None and self._loaded.key == key:
            return  # a bake shown (:meth:`show`) or loaded for these values stays
        if self._wants_orbit(scene, named):
            try:
                self._prepare_orbit(scene)
                return
            except InputFileError as exc:
                self._orbit_refused = (self._orbit_key(scene), str(exc))
                if self.values["coverage"] == "orbit":
                    raise
        if not named and not path.exists():
            self._release_loaded()
            self._shown_pem = ""
            self._missing = (
                f"no bake for scene {scene.scene.name!r} ({path.name}): showing the static EM; "
                f"bake one with `envstudio bake pem --scene {scene.scene.name} -o FILE.pem` "
                "and set pem=FILE.pem"
            )
            return
        try:
            self.show(load_pem(path), scene, path, key)
        except InputFileError:
            self.values["pem"] = self._shown_pem  # what is on show stays, and so does its name
            raise
        self._shown_pem = str(self.values["pem"])

    def _wants_orbit(self, scene: GpuScene, named: bool) -> bool:
        coverage = str(self.values["coverage"])
        if coverage == "auto":
            return (
                not named and shipped_bake(scene.scene.name).exists() and bool(scene.scene.source)
            )
        return coverage == "orbit"

    def _orbit_key(self, scene: GpuScene) -> tuple:
        """What a loaded orbit is valid for: the scene file, the scene, its environment and
        meshes (either may be replaced in place), the grid."""
        meshes = tuple(id(node.mesh) for node in scene.reflectors())
        choices = ("orbit_step", "orbit_em_size", "orbit_fit", "orbit_coupling")
        chosen = tuple(str(self.values[k]) for k in choices)
        where = (scene.scene.source, id(scene), id(scene.scene.environment))
        return ("orbit", *where, meshes, chosen)

    def _prepare_orbit(self, scene: GpuScene) -> None:
        """Load the scene's full orbit (its geometry; views come as they are needed).

        Raises
        ------
        InputFileError
            A scene not read from a file, without a reflector, or whose environment or
            meshes were replaced since (the orbit bakes the scene file's).
        """
        key = self._orbit_key(scene)
        if self._loaded is not None and self._loaded.key == key:
            return
        if self._orbit_refused is not None and self._orbit_refused[0] == key:
            raise InputFileError(self._orbit_refused[1])  # said before: not built again
        name = scene.scene.name
        if not scene.scene.source:
            raise InputFileError(f"scene {name}: not read from a scene file, so no orbit to bake")
        try:
            store = self.orbit_store(
                scene.scene.source,
                float(self.values["orbit_step"]),
                int(self.values["orbit_em_size"]),
                str(self.values["orbit_fit"]),
                float(self.values["orbit_coupling"]),
            )
        except ValueError as exc:
            raise InputFileError(f"{scene.scene.source}: {exc}") from None
        if store.plan.scene.environment.checksum() != scene.scene.environment.checksum():
            raise InputFileError(
                f"scene {name}: its environment was replaced; the full orbit bakes the scene "
                "file's (set coverage=file and bake one with `envstudio bake pem`)"
            )
        shell = store.shell()
        check_bake_for_scene(shell, scene.scene, store.folder)
        textures = ResidentViews(self.ctx, shell)
        self._release_loaded()
        self._missing = self._other_environment = ""
        models = [np.array(n.model, dtype=np.float64) for n in scene.reflectors()]
        self._loaded = _Loaded(key, store.folder, shell, textures, models, orbit=store)
        self._shown_pem = str(self.values["pem"])

    def missing_input(self) -> str | None:
        """ "needs a bake" with how to make one, while no bake is loaded for the scene."""
        return f"needs a bake: {self._missing}" if self._loaded is None and self._missing else None

    def show(self, bake: PemBake, scene: GpuScene, path: Path, key: tuple | None = None) -> None:
        """Verify ``bake`` against the scene, upload it and draw it from now on.

        Parameters
        ----------
        bake
            A loaded bake.
        scene
            The scene on show.
        path
            Its file (for messages).
        key
            What :meth:`prepare` keys the loaded bake on (None: kept until ``pem`` changes).

        Raises
        ------
        InputFileError
            A bake of another scene or mesh, or too large for this GL's textures;
            the bake shown before stays.

        Notes
        -----
        A bake of more views than :data:`~envstudio.methods.pem.resident.SLOTS` (the
        paper's 100 views at 256²: 4.2 GB of float32 maps) is not uploaded whole: its
        views move into the resident slots as the playback blends them.
        """
        check_bake_for_scene(bake, scene.scene, path)
        self._other_environment = _environment_note(bake, scene.scene, path)
        streamed = bake.views > SLOTS  # a few resident, moved in as blended (the orbit's way)
        textures = ResidentViews(self.ctx, bake) if streamed else PemTextures(self.ctx, bake)
        self._release_loaded()
        self._missing = ""
        models = [np.array(n.model, dtype=np.float64) for n in scene.reflectors()]
        key = self._key(scene) if key is None else key
        self._loaded = _Loaded(key, Path(path), bake, textures, models)

    @property
    def bake(self) -> PemBake | None:
        """The bake on show (None: none for this scene)."""
        return None if self._loaded is None else self._loaded.bake

    @property
    def orbit(self) -> OrbitStore | None:
        """The full orbit on show (None: a bake file, or none)."""
        return None if self._loaded is None else self._loaded.orbit

    # -- the camera on the path ------------------------------------------------------------

    def path_camera(self, position: float, elevation: float = 0.5) -> OrbitCamera:
        """The camera at fractions ``position`` (azimuth) and ``elevation`` of the baked path."""
        space = self.bake.view_space
        az = np.asarray(space["azimuths"], dtype=np.float64)
        el = np.asarray(space["elevations"], dtype=np.float64)
        return OrbitCamera(
            azimuth=float(np.interp(position * (len(az) - 1), np.arange(len(az)), az)),
            elevation=float(np.interp(elevation * (len(el) - 1), np.arange(len(el)), el)),
            distance=float(space["distance"]),
            target=np.asarray(space["target"], dtype=np.float64),
            fov_y=float(space["fov_y"]),
        )

    def steer_camera(self, camera: OrbitCamera) -> None:
        """Snap or play: put the camera on the baked path (seed 003's manifold)."""
        if self.bake is None or not (self.values["snap"] or self.values["play"]):
            self._last_play = None
            return
        if self.values["play"]:
            now = time.perf_counter()
            if self._last_play is not None:
                step = min(now - self._last_play, 0.1) * float(self.values["play_speed"])
                position = (float(self.values["path"]) + step) % 1.0
                self.values["path"] = position
            self._last_play = now
        on_path = self.path_camera(float(self.values["path"]), float(self.values["path_elevation"]))
        camera.azimuth, camera.elevation = on_path.azimuth, on_path.elevation
        camera.distance, camera.target, camera.fov_y = (
            on_path.distance,
            on_path.target,
            on_path.fov_y,
        )

    # -- drawing ---------------------------------------------------------------------------

    def _dummies(self) -> dict[str, moderngl.Texture]:
        if not self._dummy:
            zero = np.zeros(4, np.float32).tobytes()
            self._dummy = {
                "atlas": self.ctx.texture((1, 1), 4, zero, dtype="f4"),
                "hull": self.ctx.texture((1, 1), 1, b"\0", dtype="u1"),
            }
            for texture in self._dummy.values():
                texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
        return self._dummy

    def _bind(self, program: moderngl.Program, frame: FrameInputs) -> int:
        """Bind textures and per-frame uniforms; returns the model drawn."""
        environment = frame.scene.static_environment(frame.timer)
        environment.cube.use(location=0)
        set_uniform(program, "u_static", 0)
        loaded, dummy = self._loaded, self._dummies()
        for unit, model in zip((1, 2, 3, 5), ATLASES, strict=True):
            atlases = {} if loaded is None else loaded.textures.atlases
            atlases.get(model, dummy["atlas"]).use(location=unit)
            set_uniform(program, f"u_{model}", unit)
        (dummy["hull"] if loaded is None else loaded.textures.hull).use(location=4)
        set_uniform(program, "u_hull", 4)
        set_uniform(program, "u_camera_position", frame.camera_position)
        set_uniform(program, "u_view", frame.view)
        set_uniform(program, "u_projection", frame.projection)
        set_uniform(program, "u_sh9", frame.scene.sh9)
        set_uniform(program, "u_fresnel", tuple(self.values["fresnel"]))
        set_uniform(program, "u_kd", tuple(self.values["kd"]))
        for name in ("distant", "local", "diffuse", "hull"):
            set_uniform(program, f"u_use_{name}", bool(self.values[name]))
        set_uniform(program, "u_use_fresnel", bool(self.values["fresnel_layer"]))
        if loaded is None:
            set_uniform(program, "u_em_model", MODELS.index("static"))
            set_uniform(program, "u_use_hull", False)
            self.last_blend = None
            return MODELS.index("static")
        bake = loaded.bake
        model = MODELS.index(self._model_drawn())
        if MODELS[model] == "ptm":
            blend = ptm_blend(bake.view_space, frame.camera_position)
        else:
            blend = view_blend(bake.view_space, frame.camera_position, bool(self.values["blend"]))
        self.last_blend = blend
        views = list(blend.views)
        if loaded.orbit is not None:
            placed = self._orbit_slots(frame, blend, ptm=MODELS[model] == "ptm")
            if placed is None:  # the window: the views about the camera are still baking
                set_uniform(program, "u_em_model", MODELS.index("static"))
                set_uniform(program, "u_use_hull", False)
                return MODELS.index("static")
            blend, views = placed
            self.last_blend = blend
        elif isinstance(loaded.textures, ResidentViews):  # a large file: its views streamed
            views = loaded.textures.slots(list(blend.views), lambda v: _file_view(bake, v))
        views = views + [0] * (16 - len(views))
        weights = list(blend.weights) + [0.0] * (16 - len(blend.weights))
        set_uniform(program, "u_view_map", tuple(int(v) for v in views))  # int[16]
        set_uniform(program, "u_view_weight", tuple(float(w) for w in weights))
        set_uniform(program, "u_views_blended", len(blend.views))
        set_uniform(program, "u_parts", len(bake.parts))
        set_uniform(program, "u_atlas_width", loaded.textures.width)
        set_uniform(program, "u_hull_width", loaded.textures.width)
        set_uniform(program, "u_em_size", bake.em_size)
        set_uniform(program, "u_em_levels", len(bake.maps["distant"]))
        bias = float(bake.parameters.get("lod_bias", 0.0))
        if self.values["lod_scale"] == "bake":  # the footprint the bake's R x R image had
            bias += float(
                np.log2(frame.size[1] / float(bake.parameters.get("size", frame.size[1])))
            )
        set_uniform(program, "u_lod_bias", bias)
        set_uniform(program, "u_box_lo", bake.box[0])
        set_uniform(program, "u_box_hi", bake.box[1])
        set_uniform(program, "u_em_model", model)
        return model

    def _orbit_slots(
        self, frame: FrameInputs, blend: ViewBlend, ptm: bool = False
    ) -> tuple[ViewBlend, list[int]] | None:
        """A full orbit's blend over the views that see the reflector, and their slots.

        The views blended with a weight are baked where needed: headless now; in the
        window the background bake is asked for them (and the rest of the orbit
        after), and None is returned until they are there. A view that saw no
        reflector (a camera under the floor) leaves the blend, the others' weights
        scaled up to sum to 1 (its maps are empty, not the scene). ``ptm``: ``blend``
        is the PTM's window (weights of either sign), every view of it is baked and
        the polynomial is fitted again to those that saw the reflector.
        """
        loaded = self._loaded
        orbit = loaded.orbit
        pairs = zip(blend.views, blend.weights, strict=True)
        weighted = list(blend.views) if ptm else [v for v, w in pairs if w > 0.0]
        weighted = list(dict.fromkeys(weighted or blend.views[:1]))
        slots = loaded.textures.slots(weighted, orbit.load)
        if self.frame_budget_ms is None:
            if slots is None:
                self._bake_now(weighted)
                slots = loaded.textures.slots(weighted, orbit.load)
            if slots is None:
                raise InputFileError(f"{orbit.parts}: views {weighted} did not bake")
        else:
            if loaded.job is None:
                loaded.job = OrbitBakeJob(orbit, frame.scene.scene.source)
            target = loaded.bake.view_space["target"]
            azimuth, elevation = camera_angles(frame.camera_position, target)
            loaded.job.request(OrbitCamera(azimuth=azimuth, elevation=elevation), weighted)
            if slots is None:
                return None
        where = dict(zip(weighted, slots, strict=True))
        if ptm:
            space, eye = loaded.bake.view_space, frame.camera_position
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
        """Bake a full orbit's ``views`` before the frame (headless), a bar on a terminal."""
        from tqdm import tqdm

        orbit = self._loaded.orbit
        with tqdm(
            unit="view", desc="pem orbit", leave=False, disable=not sys.stderr.isatty()
        ) as bar:
            # a child process for the GL lookups: this one holds the frame's context
            orbit.bake(views, workers=0 if orbit.gl_lookups is None else 1, bar=bar)

    def _model_drawn(self) -> str:
        """``em_model``, or ``layered`` where it is ``ptm`` and the bake has no PTM maps."""
        model = str(self.values["em_model"])
        if model == "ptm" and (self._loaded is None or "ptm" not in self._loaded.bake.maps):
            return "layered"
        return model

    def set_part_uniforms(self, program: moderngl.Program, part: int) -> None:
        """The part's EM origin, ellipsoid and hull flags (no-op without a bake)."""
        set_uniform(program, "u_part", part)
        if self._loaded is None:
            return
        bake = self._loaded.bake
        set_uniform(program, "u_em_origin", bake.origins[part])
        set_uniform(program, "u_ellipsoid_centre", bake.ellipsoids[part, 0])
        set_uniform(program, "u_ellipsoid_radii", bake.ellipsoids[part, 1])
        set_uniform(program, "u_hull_offset", self._loaded.textures.hull_offsets[part])

    def render(self, frame: FrameInputs) -> None:
        self.prepare(frame.scene)
        if self._loaded is not None:
            now = [n.model for n in frame.scene.reflectors()]
            self._moved = not all(
                np.allclose(a, b, atol=1e-9) for a, b in zip(now, self._loaded.models, strict=True)
            )
        program = self.programs.get("pem/pem.glsl", texgen_defines(str(self.values["texgen"])))
        model = self._bind(program, frame)
        self._drawn_static = (
            self._loaded is not None
            and self._loaded.orbit is not None
            and MODELS[model] == "static"
            and self.values["em_model"] != "static"
        )
        frame.target.use()  # the static EM's capture may have bound its own framebuffer
        with frame.timer.measure("pem"):
            for part, gpu_node in enumerate(frame.scene.reflectors()):
                self.set_part_uniforms(program, part)
                set_uniform(program, "u_normal_matrix", gpu_node.normal)
                set_uniform(program, "u_model", gpu_node.model)
                gpu_node.mesh.render(program)

    # -- the panel -------------------------------------------------------------------------

    def _orbit_status(self) -> str:
        """The full orbit's progress: views baked, time left, what is on show."""
        loaded = self._loaded
        orbit, job = loaded.orbit, loaded.job
        done = len(job.done() if job is not None else orbit.done())
        line = f"full orbit: {done} of {orbit.total} views baked"
        left = None if job is None else job.seconds_left()
        if job is not None and job.failure:
            line += f" ({job.failure}; retried every {FAILED_RETRY_S:.0f} s)"
        if job is not None and job.running:
            line += " (baking nearest the camera first" + (
                f", about {left / 60:.0f} min left)" if left is not None else ")"
            )
        if self.last_blend is not None and self._drawn_static:
            return line + "; the static EM shows until the views around the camera are baked"
        return line + f"; {loaded.textures.megabytes:.0f} MB resident"

    def progress(self) -> float | None:
        """The full orbit's bake while it runs in the background (None otherwise)."""
        loaded = self._loaded
        if loaded is None or loaded.job is None or not loaded.job.running:
            return None
        return len(loaded.job.done()) / loaded.orbit.total

    def status_line(self) -> str:
        if self._missing:
            return self._missing
        if self._loaded is not None and self._loaded.orbit is not None and not self._moved:
            return self._orbit_status()
        if self._other_environment and self._loaded is not None:
            return self._other_environment
        if self._loaded is None or self.last_blend is None:
            return ""
        if self._moved:
            return (
                "the reflector was moved or turned since its bake (rotation, turntable): its "
                "reflections are those of the baked placement; reset the rotation"
            )
        bake, blend = self._loaded.bake, self.last_blend
        if self.values["em_model"] == "ptm" and "ptm" not in bake.maps:
            return (
                f"{self._loaded.path.name} has no PTM maps (baked before issue 31): showing the "
                "layered PEM; bake again with `envstudio bake pem` for the PTM"
            )
        pairs = zip(blend.views, blend.weights, strict=True)
        views = " + ".join(f"{v} ({w:.2f})" for v, w in pairs)
        textures = self._loaded.textures
        if isinstance(textures, ResidentViews):
            return (
                f"{len(textures.resident)} of {bake.views} views x {len(bake.parts)} parts "
                f"resident ({textures.megabytes:.1f} MB; the last moved in in "
                f"{textures.upload_ms:.0f} ms); blending views {views}"
            )
        return (
            f"{bake.views} views x {len(bake.parts)} parts resident ({textures.megabytes:.1f} "
            f"MB, uploaded in {textures.upload_ms:.0f} ms); blending views {views}"
        )

    def bench_notes(self) -> dict:
        """The bake on show: views resident, texture memory, the one-off upload, the blend."""
        if self._loaded is None:
            return {"bake": self._missing or "none"}
        textures, orbit = self._loaded.textures, self._loaded.orbit
        blended = 0 if self.last_blend is None else len(self.last_blend.views)
        if orbit is not None:  # the full orbit: a few views resident, moved in as needed
            return {
                "bake": f"full orbit, {orbit.describe()}",
                "views_baked": len(orbit.done()),
                "views_resident": len(textures.resident),
                "texture_mb": round(textures.megabytes, 2),
                "view_switch_upload_ms": round(textures.upload_ms, 2),
                "views_blended": blended,
            }
        if isinstance(textures, ResidentViews):  # a large file, streamed
            return {
                "bake": str(self._loaded.path),
                "views_resident": len(textures.resident),
                "texture_mb": round(textures.megabytes, 2),
                "view_switch_upload_ms": round(textures.upload_ms, 2),
                "views_blended": blended,
            }
        return {
            "bake": str(self._loaded.path),
            "views_resident": self._loaded.bake.views,
            "texture_mb": round(textures.megabytes, 2),
            "upload_ms_once": round(textures.upload_ms, 2),
            "view_switch_upload_ms": 0.0,
            "views_blended": blended,
        }

    def panel_images(self, exposure: float, tonemap: str) -> list[tuple[str, moderngl.Texture]]:
        """Figure 5: the nearest view's maps of the first part, per layer and level.

        Returns
        -------
        list of (label, texture)
            Distant, local (colour over black) and sphere maps at level 0, then the
            distant map's levels 1–4: horizontal crosses, RGBA8, owned by the method.
        """
        if self._loaded is None or self.last_blend is None:
            return []
        bake = self._loaded.bake
        view = self.last_blend.views[int(np.argmax(self.last_blend.weights))]
        maps = self._view_maps(view)
        if maps is None:
            return []
        images, labels = [], []
        for model in ("distant", "local", "sphere"):
            images.append(maps[model][0][0][..., :3])
            labels.append(f"{model}, level 0 (view {view}, {bake.parts[0]})")
        for level in range(1, min(5, len(maps["distant"]))):
            images.append(maps["distant"][level][0])
            labels.append(f"distant, level {level}")
        crosses = [upright(to_ldr(faces_to_cross(im), exposure, tonemap)) for im in images]
        if [t.size for t in self._thumbnails] != [c.shape[1::-1] for c in crosses]:
            self._release_thumbnails()
            self._thumbnails = [self.ctx.texture(c.shape[1::-1], 4) for c in crosses]
        for texture, rgb in zip(self._thumbnails, crosses, strict=True):
            alpha = np.full((*rgb.shape[:2], 1), 255, np.uint8)
            texture.write(np.ascontiguousarray(np.concatenate([rgb, alpha], axis=-1)).tobytes())
        return list(zip(labels, self._thumbnails, strict=True))

    def _view_maps(self, view: int) -> dict[str, list[np.ndarray]] | None:
        """One view's maps, model → levels of (P, 6, n_k, n_k, C) (None: not baked yet)."""
        loaded = self._loaded
        if loaded.orbit is not None:
            return loaded.orbit.load(view)
        return {m: [level[view] for level in levels] for m, levels in loaded.bake.maps.items()}

    def report_extras(self, session, out_dir: Path) -> list[ReportExtra]:
        """Seed 003 Figures 6–7 and §6's wobble, measured (methods/pem/offmanifold.py).

        At views midway between baked samples and 10° and 20° above the arc, each
        EM model against a ray trace at that exact view; the views where the
        layered PEM is not best are named. Then the mean frame-to-frame change
        along a slow sweep, per model and for the traced frames.
        """
        from envstudio.methods.pem import offmanifold

        if self.bake is None or self._loaded.orbit is not None:  # the orbit: docs/pem/orbit.md
            return []
        saved = (session.camera.azimuth, session.camera.elevation, session.camera.distance)
        saved_target, saved_fov = session.camera.target.copy(), session.camera.fov_y
        try:
            results = offmanifold.measure(session, self)
            motion = offmanifold.wobble(session, self)
        finally:
            camera = session.camera
            camera.azimuth, camera.elevation, camera.distance = saved
            camera.target, camera.fov_y = saved_target, saved_fov
        offmanifold.figure_image(results, out_dir / "pem_offmanifold.png")
        rows = [
            [
                r.view.label,
                f"{r.view.azimuth:.2f}",
                f"{r.view.elevation:.2f}",
                *(f"{r.metrics[m]['psnr']:.2f} / {r.metrics[m]['flip']:.4f}" for m in r.metrics),
                r.best,
            ]
            for r in results
        ]
        losers = [r.view.label for r in results if r.best != "layered"]
        verdict = (
            "The layered PEM is best at every view."
            if not losers
            else f"The layered PEM is not best at: {', '.join(losers)}."
        )
        wobble_text = ", ".join(f"{k} {v:.4f}" for k, v in motion.items())
        return [
            ReportExtra(
                title="PEM off the manifold (seed 003 Figures 6-7)",
                text=(
                    "Displayed PSNR (dB) / mean FLIP over the reflector's fully covered pixels, "
                    f"against a ray trace at each view. {verdict} Wobble (mean absolute "
                    f"frame-to-frame change, 0-1, along a 0.25° sweep): {wobble_text}."
                ),
                columns=["view", "azimuth °", "elevation °", *results[0].metrics, "best"],
                rows=rows,
                data={
                    "views": [
                        {
                            "label": r.view.label,
                            "azimuth": r.view.azimuth,
                            "elevation": r.view.elevation,
                            "pixels": r.pixels,
                            "metrics": r.metrics,
                            "best": r.best,
                        }
                        for r in results
                    ],
                    "layered_not_best": losers,
                    "wobble": motion,
                },
                images=[("pem_offmanifold.png", "trace | layered | sphere | static per view")],
            )
        ]

    # -- cleanup ---------------------------------------------------------------------------

    def _release_thumbnails(self) -> None:
        for texture in self._thumbnails:
            texture.release()
        self._thumbnails = []

    def _release_loaded(self) -> None:
        if self._loaded is not None:
            if self._loaded.job is not None:
                self._loaded.job.stop()
            self._loaded.textures.release()
            self._loaded = None

    def release(self) -> None:
        self._release_loaded()
        self._release_thumbnails()
        for texture in self._dummy.values():
            texture.release()
        self._dummy = {}


def _environment_note(bake: PemBake, scene: Scene, path: Path) -> str:
    """A warning when ``bake`` records another environment than the scene's (else "").

    A bake holds the far field it was traced under; played under another map it
    shows the old one. Bakes made before the record are taken as they are.
    """
    recorded = bake.parameters.get("environment")
    if recorded is None or recorded == scene.environment.checksum():
        return ""
    note = (
        f"{path.name} was baked under another environment than {scene.environment.name}: "
        "its maps show that one; bake again for this map"
    )
    print(f"envstudio: warning: {note}", file=sys.stderr)
    return note
