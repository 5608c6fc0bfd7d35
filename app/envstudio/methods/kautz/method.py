"""Method ``kautz``: seed 000 (Kautz, Daubert, Seidel 2003) and past it.

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
  b = 2, docs/kautz);
- ``sh_coefficients`` and ``lights``: the residual after taking the brightest tiles
  out as cap lights is projected to order 2, 4 or 6 (core.sh_lights), which brings
  the irradiance error on the shipped maps from a mean of 1.6–26 % (maximum 214 %)
  down to a mean of at most 0.18 % (maximum 6.2 %) with 49 coefficients and 32 lights.

The compute passes (``dynamic``, ``cross_face_filter``) need OpenGL 4.3.
"""

from __future__ import annotations

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.sh_lights import DiffuseProjector
from envstudio.envmap.conversions import read_cube
from envstudio.envmap.dynamic_cube import DynamicCube
from envstudio.envmap.mipmaps import build_cross_face_mipmaps, mipmapped_cube
from envstudio.gpu.context import has_compute, require_version
from envstudio.gpu.uniforms import set_uniform
from envstudio.plugin import FrameInputs, GpuScene, Method, Parameter
from envstudio.prefilter.brute_force import downsample_latlong
from envstudio.prefilter.sh_gpu import GpuDiffuseProjector, block_rows

#: Lat-long height of the static projection (256 × 128, section 5.1.1).
STATIC_HEIGHT = 128
#: Face size of the cube level the projection of a captured cube (dynamic or static) reads.
DYNAMIC_FACE_SIZE = 64
#: Light slots of the shader's uniform block at most.
MAX_LIGHTS = 32
_BLOCK = "KautzDiffuse"
_BLOCK_BINDING = 0


class KautzMethod(Method):
    """Single-pass diffuse (SH) and glossy (LOD-biased mip chain) reflections, seed 000."""

    name = "kautz"
    paper = "Kautz, Daubert, Seidel 2004 (seed 000)"
    title = "Kautz et al. 2003 (SH diffuse + biased mip chain)"
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
        Parameter(
            "fresnel",
            "float",
            0.26,
            0.0,
            1.0,
            "f_λ",
            "Schlick reflectance at normal incidence, weighting glossy against diffuse (eq. 8).",
        ),
        Parameter("kd", "float", 0.8, 0.0, 1.0, "k_d", "Diffuse albedo (eq. 12)."),
        Parameter(
            "per_pixel",
            "bool",
            False,
            rebuild=True,
            help="Evaluate the diffuse term and Fresnel per pixel instead of per vertex.",
        ),
        Parameter(
            "sh_coefficients",
            "choice",
            "9",
            choices=("9", "25", "49"),
            rebuild=True,
            help="SH order of the diffuse term: 9 (the paper's), 25 or 49 coefficients.",
        ),
        Parameter(
            "lights",
            "int",
            0,
            0,
            MAX_LIGHTS,
            "",
            "Brightest tiles taken out of the SH as exact cap lights (0: the paper's).",
            rebuild=True,
        ),
        Parameter(
            "light_threshold",
            "float",
            1.0,
            0.1,
            100.0,
            "× mean",
            "Texels brighter than this times the mean luminance give up their excess to lights.",
            log=True,
        ),
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
        self._rows: moderngl.Buffer | None = ctx.buffer(reserve=block_rows(49, MAX_LIGHTS) * 16)
        self._static_key: tuple | None = None
        self._projector: DiffuseProjector | None = None
        self._projector_key: tuple | None = None
        self._filtered: moderngl.TextureCube | None = None
        self._filtered_key: tuple | None = None
        self._dynamic: DynamicCube | None = None
        self._gpu_projector: GpuDiffuseProjector | None = None

    # -- rendering ---------------------------------------------------------------------------

    def render(self, frame: FrameInputs) -> None:
        scene = frame.scene
        coefficients = int(self.values["sh_coefficients"])
        lights = int(self.values["lights"])
        if self.values["dynamic"]:
            environment = self._update_dynamic(frame, coefficients, lights)
        else:
            environment = self._update_static(frame, coefficients, lights)
        frame.target.use()
        defines = {
            "PER_PIXEL": int(bool(self.values["per_pixel"])),
            "LOD_LEVEL": int(self.values["lod_mode"] == "level"),
            "SH_COEFFICIENTS": coefficients,
            "LIGHTS": lights,
        }
        program = self.programs.get("kautz/kautz.glsl", defines)
        program[_BLOCK].binding = _BLOCK_BINDING
        self._rows.bind_to_uniform_block(_BLOCK_BINDING)
        environment.use(location=0)
        set_uniform(program, "u_environment", 0)
        set_uniform(program, "u_camera_position", frame.camera_position)
        set_uniform(program, "u_lod_bias", float(self.values["lod_bias"]))
        set_uniform(program, "u_fresnel", float(self.values["fresnel"]))
        set_uniform(program, "u_kd", float(self.values["kd"]))
        set_uniform(program, "u_view", frame.view)
        set_uniform(program, "u_projection", frame.projection)
        with frame.timer.measure("kautz"):
            for gpu_node in scene.reflectors():
                set_uniform(program, "u_model", gpu_node.model)
                set_uniform(program, "u_normal_matrix", gpu_node.normal)
                gpu_node.mesh.render(program)

    def _update_static(
        self, frame: FrameInputs, coefficients: int, lights: int
    ) -> moderngl.TextureCube:
        """Project the static environment when it (or a diffuse setting) changed.

        Without local objects the lat-long map is projected on the CPU; with them,
        the captured cube (GpuScene.static_environment, seed 003 Figure 1c).
        """
        scene = frame.scene
        static = scene.static_environment(frame.timer)
        threshold = float(self.values["light_threshold"])
        key = (id(scene), static.revision, coefficients, lights, threshold)
        if key != self._static_key:
            with frame.timer.measure("kautz.project"):
                if static.captured:
                    self._project_cube(static.cube, coefficients, lights, threshold)
                else:
                    self._project_latlong(scene, coefficients, lights, threshold)
            self._static_key = key
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
            self._project_on_gpu(
                self._dynamic.cube, coefficients, lights, float(self.values["light_threshold"])
            )
        self._static_key = None  # the block now holds the dynamic lighting
        return self._dynamic.cube

    # -- helpers -----------------------------------------------------------------------------

    def _project_latlong(
        self, scene: GpuScene, coefficients: int, lights: int, threshold: float
    ) -> None:
        """Project the environment's lat-long map on the CPU into the block (section 5.1.1)."""
        radiance = _static_map(scene.scene.environment.radiance)
        projector = self._cpu_projector(
            "latlong", radiance.shape[:2], coefficients, lights, threshold
        )
        self._rows.write(np.ascontiguousarray(projector.project(radiance).block(lights)).tobytes())

    def _project_cube(
        self, cube: moderngl.TextureCube, coefficients: int, lights: int, threshold: float
    ) -> None:
        """Project a captured cube's 64² level into the block: on the GPU, or read back (3.3)."""
        if has_compute(self.ctx):
            self._project_on_gpu(cube, coefficients, lights, threshold)
            return
        faces = read_cube(cube, _projected_level(cube), self.programs)
        projector = self._cpu_projector("cube", faces.shape[1:3], coefficients, lights, threshold)
        self._rows.write(np.ascontiguousarray(projector.project(faces).block(lights)).tobytes())

    def _project_on_gpu(
        self, cube: moderngl.TextureCube, coefficients: int, lights: int, threshold: float
    ) -> None:
        """Project the cube's 64² level into the block by compute shaders (prefilter.sh_gpu)."""
        if self._gpu_projector is None:
            self._gpu_projector = GpuDiffuseProjector(self.ctx, self.programs)
        self._gpu_projector.project(
            cube, _projected_level(cube), coefficients, lights, threshold, self._rows
        )

    def _cpu_projector(
        self,
        layout: str,
        shape: tuple[int, int],
        coefficients: int,
        lights: int,
        threshold: float,
    ) -> DiffuseProjector:
        """The quadrature of a ``latlong`` (h, w) or ``cube`` (n, n) map, kept while it fits."""
        key = (layout, shape, coefficients, lights, threshold)
        if key != self._projector_key:
            options = {"coefficients": coefficients, "lights": lights, "threshold": threshold}
            if layout == "latlong":
                self._projector = DiffuseProjector.for_latlong(*shape, **options)
            else:
                self._projector = DiffuseProjector.for_cube(shape[0], **options)
            self._projector_key = key
        return self._projector

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
        for obj in (self._rows, self._filtered, self._dynamic, self._gpu_projector):
            if obj is not None:
                obj.release()
        self._rows = self._filtered = self._dynamic = self._gpu_projector = None
        self._static_key = self._filtered_key = None
        self._projector = self._projector_key = None


def _projected_level(cube: moderngl.TextureCube) -> int:
    """Mip level of ``cube`` with DYNAMIC_FACE_SIZE² faces (level 0 if smaller)."""
    return max(int(np.log2(cube.size[0] / DYNAMIC_FACE_SIZE)), 0)


def _static_map(radiance: npt.NDArray[np.float32]) -> npt.NDArray[np.float64]:
    """The environment box-filtered to at most STATIC_HEIGHT rows (power-preserving)."""
    height = radiance.shape[0]
    if height > STATIC_HEIGHT and height % STATIC_HEIGHT == 0:
        return downsample_latlong(radiance, STATIC_HEIGHT)
    return np.asarray(radiance, dtype=np.float64)
