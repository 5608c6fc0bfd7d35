"""Method ``rsibr``: reflection-space image-based rendering (seed 002, Cabral, Olano, Nemec 1999).

Precomputation (§2, §3.1, bake.rsibr): one radiance sphere map per view at the 12
icosahedron vertices, baked on the GPU from the scene's static environment
(GpuScene.static_environment) with the chosen BRDF, and cached in the user cache
folder (``$ENVSTUDIO_CACHE_DIR/rsibr``, else platformdirs' user cache) under a key
of (environment pixels, BRDF, its parameters, size, views, samples, the bake
shader). A cached file that is refused (checksum, views, size) is baked again.

Per frame (§4): the destination frame T_d is the camera's (x right, y up, z toward
the viewer, §3.3); its view direction picks the icosahedron face and the spherical
barycentric weights (§3.4); the three maps are warped through the tessellated
disk and blended into a float target with its mip chain (methods.rsibr.generator);
the reflectors are drawn sphere-mapped from it (shaders/rsibr/rsibr.glsl), with
Fresnel and the diffuse term added where the BRDF's maps do not hold them.

A change of the BRDF or of a parameter it bakes starts a new bake. Headless
(``frame_budget_ms`` None) it runs at once; in the window every bake, the first
included, runs a few views per frame within the frame budget (at least one view per
frame) while the old maps stay in use (before the first, the reflectors are not
drawn), and :meth:`progress` feeds the Method panel's progress bar.

Past the paper: ``per_pixel`` evaluates the warp per fragment instead of on the
disk's vertices (§6's future work).
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace

import moderngl
import numpy as np

from envstudio.core.rsibr_warp import view_frame
from envstudio.engine.images import to_ldr, upright
from envstudio.envmap.conversions import read_cube
from envstudio.errors import InputFileError
from envstudio.gpu.uniforms import set_uniform
from envstudio.io.cache_entries import discard
from envstudio.methods.rsibr.bake import bake as rb
from envstudio.methods.rsibr.bake.brdfs import BRDFS, brdf
from envstudio.methods.rsibr.figures import figure4
from envstudio.methods.rsibr.generator import MapGenerator
from envstudio.methods.rsibr.gpu_bake import DEFAULT_SAMPLES, GpuBaker
from envstudio.plugin import FrameInputs, Method, Parameter, StaticEnvironment

__all__ = ["RsibrMethod"]

_SHADING = {"phong": 0, "lambertian": 1, "carpaint": 2}
#: Every BRDF's bake parameters, each applying under the BRDFs that declare it.
_BAKE_PARAMETERS = {
    p.name: replace(
        p, applies_when={"brdf": tuple(n for n, b in BRDFS.items() if p in b.parameters)}
    )
    for b in BRDFS.values()
    for p in b.parameters
}


class RsibrMethod(Method):
    """Seed 002: 12 icosahedral radiance sphere maps warped and blended per frame."""

    name = "rsibr"
    paper = "Cabral, Olano, Nemec 1999 (seed 002)"
    title = "Cabral et al. 1999 (reflection-space IBR)"
    summary = (
        "Radiance sphere maps baked at the icosahedron's views, warped in reflection space "
        "and blended by spherical barycentrics per frame."
    )
    panel_figure = "Figure 4: sources, warped, generated"
    parameters = (
        Parameter(
            "brdf", "choice", "phong", unit="", help="BRDF of the maps.", choices=tuple(BRDFS)
        ),
        *_BAKE_PARAMETERS.values(),
        Parameter(
            "fresnel",
            "float",
            1.0,
            0.0,
            1.0,
            "f_λ",
            "Schlick f_λ added to Phong maps.",
            applies_when={"brdf": "phong"},
        ),
        Parameter(
            "kd",
            "float",
            0.0,
            0.0,
            1.0,
            "k_d",
            "Diffuse albedo (Phong, Lambertian).",
            applies_when={"brdf": ("phong", "lambertian")},
        ),
        Parameter(
            "warp",
            "choice",
            "auto",
            help="auto: the BRDF's (mirror for Phong and car paint, normal for Lambertian).",
            choices=("auto", "mirror", "normal"),
        ),
        Parameter("rings", "int", 16, 2, 64, "", "Disk tessellation: rings (4x as many sectors)."),
        Parameter("fade", "bool", True, help="Fade each source near its singularity (§3.3)."),
        Parameter("fade_radius", "float", 0.1, 0.01, 0.5, "", "Fade radius in map units."),
        Parameter("per_pixel", "bool", False, help="Warp per fragment (§6's future work)."),
        Parameter("map_size", "int", 64, 16, 512, "texels", "Edge of the baked maps."),
    )

    def __init__(self, ctx: moderngl.Context, programs):
        super().__init__(ctx, programs)
        self.bake: rb.RsibrBake | None = None
        self._bake_key: tuple | None = None
        self._maps: list[moderngl.Texture] = []
        self._generator: MapGenerator | None = None
        self._pending: dict | None = None
        self._wanted: tuple | None = None
        self._env_keys: dict[tuple, str] = {}
        self.last_bake_seconds: float | None = None
        #: T_d of the last frame drawn (Figure 4's destination frame).
        self.last_frame_d: np.ndarray | None = None
        self._thumbnails: list[moderngl.Texture] = []

    # -- bakes --------------------------------------------------------------------------

    def bake_values(self) -> dict[str, float]:
        """The current BRDF's bake parameters (bake.rsibr.brdfs)."""
        spec = brdf(self.values["brdf"])
        return spec.values({p.name: self.values[p.name] for p in spec.parameters})

    def _wanted_key(self, frame: FrameInputs, static: StaticEnvironment) -> tuple:
        values = tuple(sorted(self.bake_values().items()))
        return (id(frame.scene), static.revision, self.values["brdf"], values, self.map_size)

    @property
    def map_size(self) -> int:
        """Edge of the baked maps in texels."""
        return int(self.values["map_size"])

    def _update_bake(self, frame: FrameInputs, static: StaticEnvironment) -> None:
        wanted = self._wanted_key(frame, static)
        if wanted == self._bake_key:
            self._pending = None
            return
        if self._pending is None or self._pending["key"] != wanted:
            self._start(wanted, static)
        if self._pending is not None:
            budget = self.frame_budget_ms
            with frame.timer.measure("rsibr.bake"):
                self._continue(budget)

    def _start(self, key: tuple, static: StaticEnvironment) -> None:
        env_key = self._env_keys.get(key[:2])
        if env_key is None:
            env_key = rb.environment_key(read_cube(static.cube, 0, self.programs))
            self._env_keys = {key[:2]: env_key}
        name, values = key[2], dict(key[3])
        path = rb.cache_dir() / rb.cache_key(
            env_key, name, values, self.map_size, 12, DEFAULT_SAMPLES
        )
        self._pending = None
        if path.exists():
            try:
                self._install(rb.load_bake(path, size=self.map_size), key)
                return
            except InputFileError as error:  # refused: say so, bake it again
                print(f"envstudio: note: {error}; discarded, baking again", file=sys.stderr)
                discard(path)
        views, faces = rb.geodesic_views(12)
        self._pending = {
            "key": key,
            "path": path,
            "cube": static.cube,
            "env": env_key,
            "views": views,
            "faces": faces,
            "frames": np.stack([view_frame(v) for v in views]),
            "maps": [],
            "values": values,
            "start": time.perf_counter(),
        }

    def _continue(self, budget_ms: float | None) -> None:
        """Bake views until all are done or ``budget_ms`` is spent (at least one view)."""
        job = self._pending
        start = time.perf_counter()
        baker = GpuBaker(self.ctx, self.programs, self.map_size)
        try:
            while len(job["maps"]) < len(job["views"]):
                frame = job["frames"][len(job["maps"])]
                job["maps"].append(
                    baker.bake(job["cube"], job["key"][2], job["values"], frame[None])[0]
                )
                spent = 1e3 * (time.perf_counter() - start)
                more = len(job["maps"]) < len(job["views"])
                if more and budget_ms is not None and spent > budget_ms:
                    return
        finally:
            baker.release()
        bake = rb.RsibrBake(
            np.stack(job["maps"]),
            job["views"],
            job["frames"],
            job["faces"],
            job["key"][2],
            job["values"],
            DEFAULT_SAMPLES,
            "gpu",
            job["env"],
        )
        self.last_bake_seconds = time.perf_counter() - job["start"]
        job["path"].parent.mkdir(parents=True, exist_ok=True)
        rb.save_bake(job["path"], bake)
        self._install(bake, job["key"])
        self._pending = None

    def _install(self, bake: rb.RsibrBake, key: tuple) -> None:
        self._release_maps()
        for image in bake.maps:
            tex = self.ctx.texture((bake.size, bake.size), 3, image.tobytes(), dtype="f4")
            tex.repeat_x = tex.repeat_y = False
            self._maps.append(tex)
        self.bake, self._bake_key = bake, key

    # -- frames -------------------------------------------------------------------------

    def generate(self, frame_d: np.ndarray, only: int | None = None) -> moderngl.Texture:
        """The generated map for destination frame ``frame_d`` (3, 3) from the current bake.

        ``only`` warps one of the face's three sources alone (MapGenerator.generate).
        """
        if self._generator is None or self._generator.size != self.bake.size:
            if self._generator is not None:
                self._generator.release()
            self._generator = MapGenerator(self.ctx, self.programs, self.bake.size)
        warp = self.values["warp"]
        return self._generator.generate(
            self._maps,
            self.bake.views,
            self.bake.frames,
            self.bake.faces,
            frame_d,
            self.bake.warp if warp == "auto" else warp,
            rings=self.values["rings"],
            fade=self.values["fade"],
            fade_radius=self.values["fade_radius"],
            per_pixel=self.values["per_pixel"],
            only=only,
        )

    def panel_images(self, exposure: float, tonemap: str) -> list[tuple[str, moderngl.Texture]]:
        """Figure 4 of the last frame drawn, for the Method panel (methods.rsibr.figure).

        Parameters
        ----------
        exposure, tonemap
            The display's settings.

        Returns
        -------
        list of (label, texture)
            The three sources with their weights, their warped versions, the generated
            map: (n, n) RGBA8 textures, upright, owned by the method (valid until the
            next call); empty before the first bake.
        """
        if self.bake is None or self.last_frame_d is None:
            return []
        figure = figure4(self, self.last_frame_d)
        images = [*figure.sources, *figure.warped, figure.generated]
        pairs = zip(figure.indices, figure.weights, strict=True)
        labels = [f"view {i}, w = {w:.3f}" for i, w in pairs]
        labels += [f"view {i} warped" for i in figure.indices] + ["generated"]
        size = figure.generated.shape[0]
        if len(self._thumbnails) != len(images) or self._thumbnails[0].size != (size, size):
            self._release_thumbnails()
            self._thumbnails = [self.ctx.texture((size, size), 4) for _ in images]
        for texture, image in zip(self._thumbnails, images, strict=True):
            rgb = upright(to_ldr(image, exposure, tonemap))
            rgba = np.concatenate([rgb, np.full((*rgb.shape[:2], 1), 255, np.uint8)], axis=-1)
            texture.write(np.ascontiguousarray(rgba).tobytes())  # row 0 at the top, as ImGui
        return list(zip(labels, self._thumbnails, strict=True))

    def _release_thumbnails(self) -> None:
        for tex in self._thumbnails:
            tex.release()
        self._thumbnails = []

    def render(self, frame: FrameInputs) -> None:
        static = frame.scene.static_environment(frame.timer)
        self._update_bake(frame, static)
        if self.bake is None:
            return  # the window's first bake is still under way: nothing to draw yet
        frame_d = np.asarray(frame.view, dtype=np.float64)[:3, :3].T
        self.last_frame_d = frame_d
        with frame.timer.measure("rsibr.warp"):
            generated = self.generate(frame_d)
        frame.target.use()
        # the warp and the bake draw without depth test: without it again, back faces of
        # the reflector would land over front faces (and over the local objects)
        self.ctx.enable(moderngl.DEPTH_TEST)
        program = self.programs.get("rsibr/rsibr.glsl")
        generated.use(location=0)
        static.cube.use(location=1)
        set_uniform(program, "u_map", 0)
        set_uniform(program, "u_environment", 1)
        set_uniform(program, "u_camera_position", frame.camera_position)
        set_uniform(program, "u_shading", _SHADING[self.bake.brdf])
        set_uniform(program, "u_fresnel", self.values["fresnel"])
        set_uniform(program, "u_kd", self.values["kd"])
        set_uniform(program, "u_diffuse_level", frame.scene.cube_levels - 2)
        set_uniform(program, "u_view", frame.view)
        set_uniform(program, "u_projection", frame.projection)
        with frame.timer.measure("rsibr.render"):
            for gpu_node in frame.scene.reflectors():
                set_uniform(program, "u_model", gpu_node.model)
                set_uniform(program, "u_normal_matrix", gpu_node.normal)
                gpu_node.mesh.render(program)

    def finished(self) -> bool:
        return self._pending is None

    def progress(self) -> float | None:
        """Fraction of the views of the bake under way, or None when none is."""
        if self._pending is None:
            return None
        return len(self._pending["maps"]) / len(self._pending["views"])

    def status_line(self) -> str:
        if self._pending is not None:
            done, total = len(self._pending["maps"]), len(self._pending["views"])
            return f"baking {self._pending['key'][2]} maps {done}/{total}"
        return ""

    def _release_maps(self) -> None:
        for tex in self._maps:
            tex.release()
        self._maps = []

    def release(self) -> None:
        self._release_maps()
        self._release_thumbnails()
        if self._generator is not None:
            self._generator.release()
        self._generator = None
        self.bake = self._bake_key = self._pending = None
