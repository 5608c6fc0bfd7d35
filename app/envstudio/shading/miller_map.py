"""Miller's diffuse environment map: E(n)/π per direction, indexed by the normal (seed 004 §4).

Seed 004 §4 (after Miller and Hoffman 1984) prefilters the environment with the
diffuse BRDF,

    L_diffuse(n) = k_d ∫ L_i(l) ⟨n, l⟩ dl / π,

a map "only two-dimensional and indexed by the surface normal", and combines it
with the Phong environment map by eq. 2, F_d · L_diffuse + F_p · L_phong. The
methods that follow seed 004 (``hwconv``, ``banks``) read :class:`MillerDiffuseMap`:
a cube map of E(n)/π (k_d is applied in the shader), made by the project's
hierarchical prefilter (prefilter.hierarchical, seed 004 §5.1) with the cosine
kernel from the static environment (GpuScene.static_environment) box-filtered to
256 × 128, at :data:`FACE_SIZE`² texels per face. Irradiance is smooth, so its
bilinear lookups stay within 0.1 % of the exact value between texels; at the
texel centres the prefilter's threshold holds it within 0.35 % of the brute-force
irradiance on every shipped map, the sun's included (studies/compare-fairness/README.md).
"""

from __future__ import annotations

import moderngl
import numpy as np

from envstudio.core import cubemap
from envstudio.core.resample import cube_to_latlong
from envstudio.envmap.conversions import read_cube
from envstudio.gpu.programs import ProgramLibrary
from envstudio.prefilter import hierarchical, kernels
from envstudio.shading.gpu_scene import FrameInputs
from envstudio.shading.sh_irradiance import DYNAMIC_FACE_SIZE, STATIC_HEIGHT, static_map

__all__ = ["FACE_SIZE", "MillerDiffuseMap", "diffuse_faces"]

#: Texels across each face of the diffuse map.
FACE_SIZE = 32


def diffuse_faces(radiance: np.ndarray, size: int = FACE_SIZE) -> np.ndarray:
    """E(n)/π on the texel directions of a cube map (seed 004 §4's L_diffuse with k_d = 1).

    Parameters
    ----------
    radiance
        (h, w, 3) lat-long radiance (W sr⁻¹ m⁻²), row 0 = +Y.
    size
        Face edge of the result in texels.

    Returns
    -------
    (6, size, size, 3) float32
        Radiance of a white Lambertian surface with each texel's direction as normal.
    """
    return hierarchical.prefilter(radiance, cubemap.texel_directions(size), kernels.diffuse(1.0))


class MillerDiffuseMap:
    """The diffuse map of a scene's static environment, rebuilt when that changes.

    Parameters
    ----------
    ctx, programs
        Context and its program library.
    """

    def __init__(self, ctx: moderngl.Context, programs: ProgramLibrary):
        self.ctx = ctx
        self.programs = programs
        self.cube: moderngl.TextureCube | None = None
        self._key: tuple | None = None

    def update(self, frame: FrameInputs, label: str) -> moderngl.TextureCube:
        """The map for this frame's static environment, prefiltered if it changed.

        Parameters
        ----------
        frame
            This frame; the prefilter is timed as ``<label>.diffuse``.
        label
            The method's timer label.

        Returns
        -------
        moderngl.TextureCube
            (FACE_SIZE, FACE_SIZE) RGBA32F, bilinear, owned by this object.
        """
        scene = frame.scene
        static = scene.static_environment(frame.timer)
        key = (id(scene), static.revision)
        if key != self._key:
            with frame.timer.measure(f"{label}.diffuse"):
                if static.captured:
                    level = max(int(np.log2(static.cube.size[0] / DYNAMIC_FACE_SIZE)), 0)
                    faces = read_cube(static.cube, level, self.programs)
                    radiance = cube_to_latlong(faces, STATIC_HEIGHT)
                else:
                    radiance = static_map(scene.scene.environment.radiance)
                self._upload(diffuse_faces(radiance))
            self._key = key
        return self.cube

    def _upload(self, faces: np.ndarray) -> None:
        if self.cube is None:
            self.cube = self.ctx.texture_cube((FACE_SIZE, FACE_SIZE), 3, dtype="f4")
            self.cube.filter = (moderngl.LINEAR, moderngl.LINEAR)
        for face in range(6):
            self.cube.write(face, np.ascontiguousarray(faces[face], np.float32).tobytes())

    def release(self) -> None:
        """Free the cube map; safe to call twice."""
        if self.cube is not None:
            self.cube.release()
        self.cube = self._key = None
