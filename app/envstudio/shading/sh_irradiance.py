"""Irradiance from SH plus cap lights on the GPU: the diffuse term of ``kautz`` and ``mirror``.

Seed 000 §4.1 represents the irradiance E(n) by 9 SH coefficients convolved with
the clamped cosine (eq. 9–12); core.sh_lights takes the brightest tiles out as
exact cap lights first and projects the rest to order 2, 4 or 6, which brings
the mean irradiance error on the shipped maps to at most 0.18 % with 49
coefficients and 32 lights (the sun-robust setting, studies/kautz-border-and-sun).
:class:`ShIrradiance` keeps the uniform block of shaders/common/sh_irradiance.glsl
filled for a scene's static environment (GpuScene.static_environment):

- without local objects, the lat-long map box-filtered to 256 × 128 ("a very small
  environment map is sufficient", seed 000 §5.1.1), projected on the CPU with
  exact texel solid angles;
- with them (the captured static EM of seed 003 Figure 1c), the cube's 64² level,
  projected by compute shaders (prefilter.sh_gpu) or, without OpenGL 4.3, on the
  CPU from a read-back.

It projects again only when the environment or a setting changes.
"""

from __future__ import annotations

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.parameters import Parameter, ParameterValues
from envstudio.core.sh_lights import DiffuseProjector
from envstudio.envmap.conversions import read_cube
from envstudio.gpu.context import has_compute
from envstudio.gpu.programs import ProgramLibrary
from envstudio.prefilter.brute_force import downsample_latlong
from envstudio.prefilter.sh_gpu import GpuDiffuseProjector, block_rows
from envstudio.shading.gpu_scene import FrameInputs, GpuScene

__all__ = [
    "DYNAMIC_FACE_SIZE",
    "MAX_LIGHTS",
    "STATIC_HEIGHT",
    "ShIrradiance",
    "sh_parameters",
    "static_map",
]

#: Lat-long height of the static projection (256 × 128, seed 000 §5.1.1).
STATIC_HEIGHT = 128
#: Face size of the cube level the projection of a captured cube reads.
DYNAMIC_FACE_SIZE = 64
#: Light slots of the shader's uniform block at most.
MAX_LIGHTS = 32
_BLOCK = "ShIrradiance"
_BLOCK_BINDING = 0


def sh_parameters(coefficients: str = "9", lights: int = 0) -> tuple[Parameter, ...]:
    """``sh_coefficients``, ``lights`` and ``light_threshold`` with the given defaults.

    Parameters
    ----------
    coefficients
        Default SH coefficient count: "9" (seed 000's), "25" or "49".
    lights
        Default number of cap lights (0: seed 000's; 32 with "49": sun-robust).
    """
    return (
        Parameter(
            "sh_coefficients",
            "choice",
            coefficients,
            choices=("9", "25", "49"),
            rebuild=True,
            help="SH order of the diffuse term: 9 (the paper's), 25 or 49 coefficients.",
        ),
        Parameter(
            "lights",
            "int",
            lights,
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
    )


class ShIrradiance:
    """The uniform block of common/sh_irradiance.glsl for one method.

    Parameters
    ----------
    ctx, programs
        Context and its program library.
    """

    def __init__(self, ctx: moderngl.Context, programs: ProgramLibrary):
        self.ctx = ctx
        self.programs = programs
        self.rows: moderngl.Buffer | None = ctx.buffer(reserve=block_rows(49, MAX_LIGHTS) * 16)
        self._static_key: tuple | None = None
        self._projector: DiffuseProjector | None = None
        self._projector_key: tuple | None = None
        self._gpu_projector: GpuDiffuseProjector | None = None

    @staticmethod
    def defines(values: ParameterValues) -> dict[str, int]:
        """SH_COEFFICIENTS and LIGHTS of the shader for the method's values."""
        return {
            "SH_COEFFICIENTS": int(values["sh_coefficients"]),
            "LIGHTS": int(values["lights"]),
        }

    def update_static(self, frame: FrameInputs, values: ParameterValues, label: str) -> None:
        """Project the static environment when it (or a diffuse setting) changed.

        Parameters
        ----------
        frame
            This frame (its scene's static environment; the projection is timed
            as ``<label>.project``).
        values
            The method's ``sh_coefficients``, ``lights`` and ``light_threshold``.
        label
            The method's timer label.
        """
        scene = frame.scene
        static = scene.static_environment(frame.timer)
        coefficients, lights = int(values["sh_coefficients"]), int(values["lights"])
        threshold = float(values["light_threshold"])
        key = (id(scene), static.revision, coefficients, lights, threshold)
        if key == self._static_key:
            return
        with frame.timer.measure(f"{label}.project"):
            if static.captured:
                self._project_cube(static.cube, coefficients, lights, threshold)
            else:
                self._project_latlong(scene, coefficients, lights, threshold)
        self._static_key = key

    def project_on_gpu(
        self, cube: moderngl.TextureCube, coefficients: int, lights: int, threshold: float
    ) -> None:
        """Project the cube's 64² level into the block by compute shaders (prefilter.sh_gpu).

        For a cube that changes every frame (kautz's ``dynamic``); the next
        :meth:`update_static` projects the static environment again.
        """
        if self._gpu_projector is None:
            self._gpu_projector = GpuDiffuseProjector(self.ctx, self.programs)
        self._gpu_projector.project(
            cube, _projected_level(cube), coefficients, lights, threshold, self.rows
        )
        self._static_key = None

    def bind(self, program: moderngl.Program) -> None:
        """Bind the block to ``program``'s ShIrradiance."""
        program[_BLOCK].binding = _BLOCK_BINDING
        self.rows.bind_to_uniform_block(_BLOCK_BINDING)

    def _project_latlong(
        self, scene: GpuScene, coefficients: int, lights: int, threshold: float
    ) -> None:
        """Project the environment's lat-long map on the CPU into the block (§5.1.1)."""
        radiance = static_map(scene.scene.environment.radiance)
        projector = self._cpu_projector(
            "latlong", radiance.shape[:2], coefficients, lights, threshold
        )
        self.rows.write(np.ascontiguousarray(projector.project(radiance).block(lights)).tobytes())

    def _project_cube(
        self, cube: moderngl.TextureCube, coefficients: int, lights: int, threshold: float
    ) -> None:
        """Project a captured cube's 64² level: on the GPU, or read back (OpenGL 3.3)."""
        if has_compute(self.ctx):
            self.project_on_gpu(cube, coefficients, lights, threshold)
            return
        faces = read_cube(cube, _projected_level(cube), self.programs)
        projector = self._cpu_projector("cube", faces.shape[1:3], coefficients, lights, threshold)
        self.rows.write(np.ascontiguousarray(projector.project(faces).block(lights)).tobytes())

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

    def release(self) -> None:
        """Free the block buffer and the GPU projector; safe to call twice."""
        for obj in (self.rows, self._gpu_projector):
            if obj is not None:
                obj.release()
        self.rows = self._gpu_projector = None
        self._static_key = self._projector = self._projector_key = None


def _projected_level(cube: moderngl.TextureCube) -> int:
    """Mip level of ``cube`` with DYNAMIC_FACE_SIZE² faces (level 0 if smaller)."""
    return max(int(np.log2(cube.size[0] / DYNAMIC_FACE_SIZE)), 0)


def static_map(radiance: npt.NDArray[np.float32]) -> npt.NDArray[np.float64]:
    """The environment box-filtered to at most STATIC_HEIGHT rows (power-preserving)."""
    height = radiance.shape[0]
    if height > STATIC_HEIGHT and height % STATIC_HEIGHT == 0:
        return downsample_latlong(radiance, STATIC_HEIGHT)
    return np.asarray(radiance, dtype=np.float64)
