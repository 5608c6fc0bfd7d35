"""Method ``kautz``: seed 000 (Kautz, Daubert, Seidel 2004) and past it.

One pass draws every reflector with (shaders/kautz/kautz.glsl)

- the diffuse term of section 4.1: the irradiance E(n) from SH coefficients
  (eq. 9–12), per vertex in the vertex shader or, with ``per_pixel``, per fragment,
  times k_d / π;
- the glossy term of sections 4.2 and 5.2: the cube map's mip chain looked up along
  the reflection vector with the LOD bias b, ``texture(cube, r, b)``;
- Schlick's Fresnel term with the single parameter f_λ (section 5.2), per vertex or
  per fragment, combining the two by eq. 8.

Where the lighting comes from:

- static environment, no local objects: the environment's lat-long map,
  box-filtered to 256 × 128 ("a very small environment map is sufficient",
  section 5.1.1), is projected on the CPU with exact texel solid angles whenever
  the environment (or a diffuse parameter) changes; the glossy lookups use the
  shared cube map and its hardware box-filtered mip chain;
- static environment with local objects (the room): seed 003's static EM
  (Figure 1c), GpuScene.static_environment, the local objects captured over the
  environment from the reflector's centre once per scene change; its mip chain
  serves the glossy lookups and its 64² level is projected as in ``dynamic``
  (on the CPU from a read-back where the context has no compute shaders);
- ``dynamic`` (section 5.1): every frame the local objects are rendered into the six
  faces of a cube map from the reflector's centre over the environment
  (envmap.dynamic_cube), the mip chain is rebuilt, and the SH coefficients (and
  lights) are projected from its 64² level by compute shaders (prefilter.sh_gpu) —
  no pixel goes back to the CPU.

Past the paper:

- ``cross_face_filter``: the mip chain is built by a tent filter that crosses face
  edges (envmap.mipmaps, the border problem of Figure 4);
- ``lod_mode=level``: b is the mip level itself rather than a bias on the hardware's
  screen-space LOD, so the blur does not change with the image size and matches the
  b ↔ N fit of prefilter.glossiness (PSNR 12.7 → 23.6 dB against the Phong reference at
  b = 2, studies/kautz-border-and-sun);
- ``sh_coefficients`` and ``lights``: the residual after taking the brightest tiles
  out as cap lights is projected to order 2, 4 or 6 (core.sh_lights), which brings
  the irradiance error on the shipped maps from a mean of 1.6–26 % (maximum 214 %)
  down to a mean of at most 0.18 % (maximum 6.2 %) with 49 coefficients and 32 lights.

The compute passes (``dynamic``, ``cross_face_filter``) need OpenGL 4.3.
"""

from __future__ import annotations

import moderngl

from envstudio.envmap.dynamic_cube import DynamicCube
from envstudio.envmap.mipmaps import build_cross_face_mipmaps, mipmapped_cube
from envstudio.gpu.context import require_version
from envstudio.plugin import (
    FrameInputs,
    Method,
    Parameter,
    ShIrradiance,
    fresnel_parameter,
    kd_parameter,
    set_uniform,
    sh_parameters,
)
from envstudio.shading.sh_irradiance import STATIC_HEIGHT

__all__ = ["STATIC_HEIGHT", "KautzMethod"]


class KautzMethod(Method):
    """Single-pass diffuse (SH) and glossy (LOD-biased mip chain) reflections, seed 000."""

    name = "kautz"
    paper = "Kautz, Daubert, Seidel 2004 (seed 000)"
    title = "Kautz et al. 2004 (SH diffuse + biased mip chain)"
    summary = (
        "Diffuse from SH irradiance, glossy from the box-filtered cube mip chain with LOD "
        "bias b, Schlick Fresnel; dynamic cube capture; cross-face mips; sun extraction."
    )
    parameters = (
        Parameter(
            "lod_bias",
            "float",
            1.7,
            0.0,
            12.0,
            "b",
            "LOD bias of the glossy cube-map lookup: higher is blurrier (section 5.2).",
        ),
        Parameter(
            "lod_mode",
            "choice",
            "bias",
            choices=("bias", "level"),
            rebuild=True,
            help="bias: b is added to the hardware LOD (the paper); level: b is the mip level "
            "itself, never finer than a pixel (resolution-independent, as the b-N fit assumes).",
        ),
        fresnel_parameter(
            0.26,
            "Schlick reflectance at normal incidence per RGB channel, weighting glossy against "
            "diffuse (eq. 8).",
        ),
        kd_parameter(0.8, "Diffuse albedo per RGB channel (eq. 12)."),
        Parameter(
            "per_pixel",
            "bool",
            False,
            rebuild=True,
            help="Evaluate the diffuse term and Fresnel per pixel instead of per vertex.",
        ),
        *sh_parameters(),
        Parameter(
            "dynamic",
            "bool",
            False,
            rebuild=True,
            help="Re-render the cube map from the reflector every frame, with the local "
            "objects, and rebuild mips and SH on the GPU (section 5.1).",
        ),
        Parameter(
            "cross_face_filter",
            "bool",
            False,
            rebuild=True,
            help="Build the mip chain with a filter that crosses face edges (no seams "
            "at high b, Figure 4).",
        ),
    )

    def __init__(self, ctx: moderngl.Context, programs):
        super().__init__(ctx, programs)
        self._irradiance: ShIrradiance | None = ShIrradiance(ctx, programs)
        self._filtered: moderngl.TextureCube | None = None
        self._filtered_key: tuple | None = None
        self._dynamic: DynamicCube | None = None

    # -- rendering ---------------------------------------------------------------------------

    def render(self, frame: FrameInputs) -> None:
        coefficients = int(self.values["sh_coefficients"])
        lights = int(self.values["lights"])
        if self.values["dynamic"]:
            environment = self._update_dynamic(frame, coefficients, lights)
        else:
            environment = self._update_static(frame)
        frame.target.use()
        defines = {
            "PER_PIXEL": int(bool(self.values["per_pixel"])),
            "LOD_LEVEL": int(self.values["lod_mode"] == "level"),
            **ShIrradiance.defines(self.values),
        }
        program = self.programs.get("kautz/kautz.glsl", defines)
        self._irradiance.bind(program)
        environment.use(location=0)
        set_uniform(program, "u_environment", 0)
        set_uniform(program, "u_camera_position", frame.camera_position)
        set_uniform(program, "u_lod_bias", float(self.values["lod_bias"]))
        set_uniform(program, "u_fresnel", tuple(self.values["fresnel"]))
        set_uniform(program, "u_kd", tuple(self.values["kd"]))
        with frame.timer.measure("kautz"):
            frame.draw_reflectors(program)

    def _update_static(self, frame: FrameInputs) -> moderngl.TextureCube:
        """The static environment's cube (or its cross-face chain), its SH projected.

        Without local objects the lat-long map is projected on the CPU; with them,
        the captured cube (GpuScene.static_environment, seed 003 Figure 1c).
        """
        scene = frame.scene
        static = scene.static_environment(frame.timer)
        self._irradiance.update_static(frame, self.values, "kautz")
        if not self.values["cross_face_filter"]:
            return static.cube
        filtered_key = (id(scene), static.revision)
        if filtered_key != self._filtered_key:
            self._require_compute("cross_face_filter")
            with frame.timer.measure("kautz.mipmaps"):
                self._build_filtered(static.cube)
            self._filtered_key = filtered_key
        return self._filtered

    def _update_dynamic(
        self, frame: FrameInputs, coefficients: int, lights: int
    ) -> moderngl.TextureCube:
        """Capture the cube map, rebuild its mip chain and project it, all on the GPU."""
        self._require_compute("dynamic")
        scene = frame.scene
        size = scene.cube_size
        if self._dynamic is None or self._dynamic.size != size:
            if self._dynamic is not None:
                self._dynamic.release()
            self._dynamic = DynamicCube(self.ctx, self.programs, size)
        objects = scene.local_capture_objects()
        with frame.timer.measure("kautz.capture"):
            self._dynamic.capture(scene.cube, scene.sh9, objects, scene.reflector_centre())
        with frame.timer.measure("kautz.mipmaps"):
            self._dynamic.build_mipmaps(bool(self.values["cross_face_filter"]))
        with frame.timer.measure("kautz.sh"):
            self._irradiance.project_on_gpu(
                self._dynamic.cube, coefficients, lights, float(self.values["light_threshold"])
            )
        return self._dynamic.cube

    # -- helpers -----------------------------------------------------------------------------

    def _build_filtered(self, source: moderngl.TextureCube) -> None:
        """Copy level 0 of ``source`` (on the GPU) and build the cross-face chain from it."""
        size = source.size[0]
        if self._filtered is None or self._filtered.size[0] != size:
            if self._filtered is not None:
                self._filtered.release()
            self._filtered = mipmapped_cube(self.ctx, size)
        pixels = self.ctx.buffer(reserve=size * size * 16)
        try:
            for face in range(6):
                source.read_into(pixels, face)
                self._filtered.write(face, pixels)
        finally:
            pixels.release()
        build_cross_face_mipmaps(self.ctx, self.programs, self._filtered)

    def _require_compute(self, feature: str) -> None:
        require_version(self.ctx, 430, f"{feature}=true needs OpenGL 4.3 compute shaders")

    # -- resources ---------------------------------------------------------------------------

    def release(self) -> None:
        """Free the block buffer, the filtered and dynamic cube maps; safe to call twice."""
        for obj in (self._irradiance, self._filtered, self._dynamic):
            if obj is not None:
                obj.release()
        self._irradiance = self._filtered = self._dynamic = None
        self._filtered_key = None
