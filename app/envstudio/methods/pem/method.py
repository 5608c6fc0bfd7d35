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

The method picks what to play and draws it; its parts: a ``.pem`` file's maps on
the GPU (methods/pem/file_playback.py), the full orbit (issue 31, ``coverage``: a
scene that ships a bake plays every view the orbit camera reaches, baked on first
use, methods/pem/orbit_playback.py), the shader's inputs
(methods/pem/shader_inputs.py), the camera on the baked path
(methods/pem/path_steering.py), the panel's Figure 5 (methods/pem/panel_figure.py)
and ``compare``'s section (methods/pem/offmanifold_report.py).
"""

from __future__ import annotations

from pathlib import Path

import moderngl
import numpy as np

from envstudio.methods.pem.bake.orbit import OrbitStore
from envstudio.methods.pem.bake.pem_file import PemBake, load_pem
from envstudio.methods.pem.blending import ViewBlend, ptm_blend, view_blend
from envstudio.methods.pem.file_playback import FilePlayback, environment_note
from envstudio.methods.pem.gpu import MODELS, texgen_defines
from envstudio.methods.pem.orbit_playback import (
    OrbitPlayback,
    full_orbit_store,
    orbit_playback_key,
)
from envstudio.methods.pem.panel_figure import NearestViewFigure
from envstudio.methods.pem.parameters import PEM_PARAMETERS
from envstudio.methods.pem.path_steering import PathSteering
from envstudio.methods.pem.shader_inputs import PemShaderInputs
from envstudio.methods.pem.verify import check_bake_for_scene
from envstudio.plugin import (
    FrameInputs,
    GpuScene,
    InputFileError,
    Method,
    ReportExtra,
    set_uniform,
)
from envstudio.resources import asset_root
from envstudio.scene.camera import OrbitCamera

__all__ = ["PemMethod", "shipped_bake"]


def shipped_bake(scene_name: str) -> Path:
    """Where a scene's shipped bake lives: ``assets/pem/<scene>.pem``."""
    return asset_root() / "pem" / f"{scene_name}.pem"


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
    parameters = PEM_PARAMETERS

    #: The full orbit of a scene file (methods/pem/orbit_playback.py; a test swaps it).
    orbit_store = staticmethod(full_orbit_store)

    def __init__(self, ctx: moderngl.Context, programs):
        super().__init__(ctx, programs)
        self._loaded: FilePlayback | OrbitPlayback | None = None
        self._missing: str = ""
        self._other_environment = ""  # the bake's recorded environment is not the scene's
        self._inputs = PemShaderInputs(ctx)
        self._figure = NearestViewFigure(ctx)
        self._steering = PathSteering()
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
                self._orbit_refused = (orbit_playback_key(scene, self.values), str(exc))
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

    def _prepare_orbit(self, scene: GpuScene) -> None:
        """Load the scene's full orbit (its geometry; views come as they are needed).

        Raises
        ------
        InputFileError
            A scene not read from a file, without a reflector, or whose environment or
            meshes were replaced since (the orbit bakes the scene file's).
        """
        key = orbit_playback_key(scene, self.values)
        if self._loaded is not None and self._loaded.key == key:
            return
        if self._orbit_refused is not None and self._orbit_refused[0] == key:
            raise InputFileError(self._orbit_refused[1])  # said before: not built again
        if not scene.scene.source:
            raise InputFileError(
                f"scene {scene.scene.name}: not read from a scene file, so no orbit to bake"
            )
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
        orbit = OrbitPlayback(self.ctx, store, scene, key)
        self._release_loaded()
        self._missing = self._other_environment = ""
        self._loaded = orbit
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
        self._other_environment = environment_note(bake, scene.scene, path)
        models = [np.array(n.model, dtype=np.float64) for n in scene.reflectors()]
        key = self._key(scene) if key is None else key
        playback = FilePlayback(self.ctx, bake, Path(path), key, models)
        self._release_loaded()
        self._missing = ""
        self._loaded = playback

    @property
    def bake(self) -> PemBake | None:
        """The bake on show (None: none for this scene)."""
        return None if self._loaded is None else self._loaded.bake

    @property
    def orbit(self) -> OrbitStore | None:
        """The full orbit on show (None: a bake file, or none)."""
        return self._loaded.orbit if isinstance(self._loaded, OrbitPlayback) else None

    def steer_camera(self, camera: OrbitCamera) -> None:
        """Snap or play: put the camera on the baked path (seed 003's manifold)."""
        self._steering.steer(camera, self.bake, self.values)

    # -- drawing ---------------------------------------------------------------------------

    def _bind(self, program: moderngl.Program, frame: FrameInputs) -> str:
        """Bind textures and per-frame uniforms; returns the model drawn (of ``MODELS``)."""
        loaded = self._loaded
        environment = frame.scene.static_environment(frame.timer)
        textures = None if loaded is None else loaded.textures
        self._inputs.bind_maps(program, environment.cube, textures)
        self._inputs.set_layers(program, frame, self.values)
        if loaded is None:
            self._inputs.show_static(program)
            self.last_blend = None
            return "static"
        bake, model = loaded.bake, self._model_drawn()
        if model == "ptm":
            blend = ptm_blend(bake.view_space, frame.camera_position)
        else:
            blend = view_blend(bake.view_space, frame.camera_position, bool(self.values["blend"]))
        self.last_blend = blend
        if isinstance(loaded, OrbitPlayback):
            budgeted = self.frame_budget_ms is not None
            placed = loaded.place(frame, blend, ptm=model == "ptm", budgeted=budgeted)
            if placed is None:  # the window: the views about the camera are still baking
                self._inputs.show_static(program)
                return "static"
        else:
            placed = loaded.place(blend)
        self.last_blend, views = placed
        self._inputs.set_blend(program, self.last_blend, views)
        self._inputs.set_bake(program, frame, bake, loaded.textures, str(self.values["lod_scale"]))
        set_uniform(program, "u_em_model", MODELS.index(model))
        return model

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
            self.orbit is not None and model == "static" and self.values["em_model"] != "static"
        )
        frame.target.use()  # the static EM's capture may have bound its own framebuffer
        with frame.timer.measure("pem"):
            for part, gpu_node in enumerate(frame.scene.reflectors()):
                self.set_part_uniforms(program, part)
                set_uniform(program, "u_normal_matrix", gpu_node.normal)
                set_uniform(program, "u_model", gpu_node.model)
                gpu_node.mesh.render(program)

    # -- the panel and the reports ---------------------------------------------------------

    def progress(self) -> float | None:
        """The full orbit's bake while it runs in the background (None otherwise)."""
        return self._loaded.progress() if isinstance(self._loaded, OrbitPlayback) else None

    def status_line(self) -> str:
        loaded = self._loaded
        if self._missing:
            return self._missing
        if isinstance(loaded, OrbitPlayback) and not self._moved:
            return loaded.progress_line(self.last_blend is not None and self._drawn_static)
        if self._other_environment and loaded is not None:
            return self._other_environment
        if loaded is None or self.last_blend is None:
            return ""
        if self._moved:
            return (
                "the reflector was moved or turned since its bake (rotation, turntable): its "
                "reflections are those of the baked placement; reset the rotation"
            )
        if self.values["em_model"] == "ptm" and "ptm" not in loaded.bake.maps:
            return (
                f"{loaded.path.name} has no PTM maps (baked before issue 31): showing the "
                "layered PEM; bake again with `envstudio bake pem` for the PTM"
            )
        return loaded.residency_line(self.last_blend)

    def bench_notes(self) -> dict:
        """The bake on show: views resident, texture memory, the one-off upload, the blend."""
        if self._loaded is None:
            return {"bake": self._missing or "none"}
        blended = 0 if self.last_blend is None else len(self.last_blend.views)
        return self._loaded.bench_notes(blended)

    def panel_images(self, exposure: float, tonemap: str) -> list[tuple[str, moderngl.Texture]]:
        """Figure 5: the nearest view's maps of the first part, per layer and level.

        Returns
        -------
        list of (label, texture)
            Distant, local (colour over black) and sphere maps at level 0, then the
            distant map's levels 1–4: horizontal crosses, RGBA8, owned by the method.
        """
        loaded = self._loaded
        if loaded is None or self.last_blend is None:
            return []
        return self._figure.images(
            loaded.bake, loaded.view_maps, self.last_blend, exposure, tonemap
        )

    def report_extras(self, session, out_dir: Path) -> list[ReportExtra]:
        """Seed 003 Figures 6–7 and §6's wobble, measured for a bake file
        (methods/pem/offmanifold_report.py; none for the full orbit:
        studies/pem-orbit/README.md)."""
        from envstudio.methods.pem.offmanifold_report import offmanifold_extra

        if self.bake is None or self.orbit is not None:
            return []
        return [offmanifold_extra(session, self, out_dir)]

    # -- cleanup ---------------------------------------------------------------------------

    def _release_loaded(self) -> None:
        if self._loaded is not None:
            self._loaded.release()
            self._loaded = None

    def release(self) -> None:
        self._release_loaded()
        self._figure.release()
        self._inputs.release()
