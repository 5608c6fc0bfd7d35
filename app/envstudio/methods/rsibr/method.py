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
Fresnel and the diffuse term added where the BRDF's maps do not hold them. For
Phong with k_d > 0 the diffuse term is the paper's own (§3): a second set of 12
Lambertian maps, warped by the normal and blended the same way
(methods.rsibr.map_set), read at the same texel (the texel of r is that of n).

A change of the BRDF or of a parameter it bakes starts a new bake. Headless
(``frame_budget_ms`` None) it runs at once; in the window every bake, the first
included, runs a few views per frame within the frame budget (at least one view per
frame) while the old maps stay in use (before the first, the reflectors are not
drawn), and :meth:`progress` feeds the Method panel's progress bar.

Past the paper: ``per_pixel`` evaluates the warp per fragment instead of on the
disk's vertices (§6's future work).
"""

from __future__ import annotations

from dataclasses import replace

import moderngl
import numpy as np

from envstudio.methods.rsibr.bake import bake as rb
from envstudio.methods.rsibr.bake.brdfs import BRDFS, brdf
from envstudio.methods.rsibr.figures import figure4
from envstudio.methods.rsibr.generator import MapGenerator
from envstudio.methods.rsibr.gpu_bake import DEFAULT_SAMPLES
from envstudio.methods.rsibr.map_set import MapSet
from envstudio.plugin import (
    FrameInputs,
    Method,
    MillerDiffuseMap,
    Parameter,
    StaticEnvironment,
    fresnel_parameter,
    kd_parameter,
    set_uniform,
    to_ldr,
    upright,
)

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
        fresnel_parameter(
            1.0, "Schlick f_λ added to Phong maps, per RGB channel.", applies_when={"brdf": "phong"}
        ),
        kd_parameter(
            0.0,
            "Diffuse albedo (Phong, Lambertian), per RGB channel.",
            applies_when={"brdf": ("phong", "lambertian")},
        ),
        Parameter(
            "diffuse_maps",
            "choice",
            "prefiltered",
            choices=("prefiltered", "baked"),
            help="Lambertian maps of k_d: prefiltered (each texel E(n)/pi from Miller's map, "
            "shading/miller_map.py) or baked (importance-sampled, diffuse_samples).",
            applies_when={"brdf": "phong"},
        ),
        Parameter(
            "diffuse_samples",
            "int",
            1024,
            64,
            16384,
            "",
            "Importance samples per texel of the Lambertian maps of k_d (256: as the BRDF's "
            "maps; a sun needs 1024 for 1 % irradiance error).",
            log=True,
            applies_when={"brdf": "phong"},
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
        self._glossy = MapSet(ctx, programs)
        self._diffuse = MapSet(ctx, programs)
        self._miller = MillerDiffuseMap(ctx, programs)
        #: T_d of the last frame drawn (Figure 4's destination frame).
        self.last_frame_d: np.ndarray | None = None
        self._thumbnails: list[moderngl.Texture] = []

    # -- bakes --------------------------------------------------------------------------

    @property
    def bake(self) -> rb.RsibrBake | None:
        """The BRDF's installed bake, or None before the first."""
        return self._glossy.bake

    @property
    def last_bake_seconds(self) -> float | None:
        """Seconds the BRDF's last bake took; None when it came from the cache."""
        return self._glossy.last_bake_seconds

    def bake_values(self) -> dict[str, float]:
        """The current BRDF's bake parameters (bake.rsibr.brdfs)."""
        spec = brdf(self.values["brdf"])
        return spec.values({p.name: self.values[p.name] for p in spec.parameters})

    @property
    def map_size(self) -> int:
        """Edge of the baked maps in texels."""
        return int(self.values["map_size"])

    def _needs_diffuse_maps(self) -> bool:
        """Phong with k_d > 0: its diffuse term comes from Lambertian maps (seed 002 §3)."""
        return self.values["brdf"] == "phong" and max(self.values["kd"]) > 0.0

    def _update_bakes(self, frame: FrameInputs, static: StaticEnvironment) -> None:
        scene_key = (id(frame.scene), static.revision)
        values = tuple(sorted(self.bake_values().items()))
        glossy = (*scene_key, self.values["brdf"], values, self.map_size, DEFAULT_SAMPLES)
        wanted = [(self._glossy, glossy, None)]
        if self._needs_diffuse_maps():
            prefiltered = self.values["diffuse_maps"] == "prefiltered"
            samples = 0 if prefiltered else int(self.values["diffuse_samples"])
            diffuse = (*scene_key, "lambertian", (), self.map_size, samples)
            source = self._miller.update(frame, "rsibr") if prefiltered else None
            wanted.append((self._diffuse, diffuse, source))
        with frame.timer.measure("rsibr.bake"):
            for maps, key, source in wanted:
                maps.update(key, static, self.frame_budget_ms, source)
                if maps.pending is not None:
                    return  # one bake at a time within the frame budget

    # -- frames -------------------------------------------------------------------------

    def generate(self, frame_d: np.ndarray, only: int | None = None) -> moderngl.Texture:
        """The generated map for destination frame ``frame_d`` (3, 3) from the current bake.

        ``only`` warps one of the face's three sources alone (MapGenerator.generate).
        """
        warp = self.values["warp"]
        return self._glossy.generate(
            frame_d, self.bake.warp if warp == "auto" else warp, only=only, **self._warp_options()
        )

    @property
    def generator(self) -> MapGenerator | None:
        """The BRDF maps' generator of the last :meth:`generate` (Figure 4)."""
        return self._glossy.generator

    def _warp_options(self) -> dict:
        return {
            "rings": self.values["rings"],
            "fade": self.values["fade"],
            "fade_radius": self.values["fade_radius"],
            "per_pixel": self.values["per_pixel"],
        }

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
        self._update_bakes(frame, static)
        if self.bake is None:
            return  # the window's first bake is still under way: nothing to draw yet
        frame_d = np.asarray(frame.view, dtype=np.float64)[:3, :3].T
        self.last_frame_d = frame_d
        with frame.timer.measure("rsibr.warp"):
            generated = self.generate(frame_d)
            diffuse = self._diffuse_map(frame_d)
        frame.target.use()
        # the warp and the bake draw without depth test: without it again, back faces of
        # the reflector would land over front faces (and over the local objects)
        self.ctx.enable(moderngl.DEPTH_TEST)
        program = self.programs.get("rsibr/rsibr.glsl")
        generated.use(location=0)
        set_uniform(program, "u_map", 0)
        if diffuse is not None:
            diffuse.use(location=1)
        set_uniform(program, "u_diffuse_map", 1)
        set_uniform(program, "u_has_diffuse_map", diffuse is not None)
        set_uniform(program, "u_camera_position", frame.camera_position)
        set_uniform(program, "u_shading", _SHADING[self.bake.brdf])
        set_uniform(program, "u_fresnel", tuple(self.values["fresnel"]))
        set_uniform(program, "u_kd", tuple(self.values["kd"]))
        with frame.timer.measure("rsibr.render"):
            frame.draw_reflectors(program)

    def _diffuse_map(self, frame_d: np.ndarray) -> moderngl.Texture | None:
        """The normal-warped Lambertian map for T_d, or None where none applies or is baked."""
        if not self._needs_diffuse_maps() or self._diffuse.bake is None:
            return None
        return self._diffuse.generate(frame_d, "normal", **self._warp_options())

    def _pending(self) -> dict | None:
        for maps in (self._glossy, self._diffuse):
            if maps.pending is not None:
                return maps.pending
        return None

    def finished(self) -> bool:
        return self._pending() is None

    def progress(self) -> float | None:
        """Fraction of the views of the bake under way, or None when none is."""
        pending = self._pending()
        if pending is None:
            return None
        return len(pending["maps"]) / len(pending["views"])

    def status_line(self) -> str:
        pending = self._pending()
        if pending is not None:
            done, total = len(pending["maps"]), len(pending["views"])
            return f"baking {pending['key'][2]} maps {done}/{total}"
        return ""

    def release(self) -> None:
        self._glossy.release()
        self._diffuse.release()
        self._miller.release()
        self._release_thumbnails()
