"""The 3D map L_banks(t, ⟨v,t⟩) of seed 004 §5.3, built on the GPU or in NumPy.

Both builders evaluate the ring form of methods/banks/lobe.py from the static
environment's cube map (its box mip level whose texels are about one ring bin
wide, :func:`ring_level`):

1. rings: R_t(θ_k) = 2π/M Σ_m L(ring point m), for every tangent texel t of the
   front paraboloid face (with border) and every bin k — (T, T, K) values;
2. slices: L_banks(t, cos θ_v,j) = Σ_k w_k(θ_v,j) R_t(θ_k) for every slice j, and
   in alpha the same sum for a unit environment, 2π Σ_k w_k (the lobe's
   integral at that slice, :func:`envstudio.methods.banks.lobe.lobe_integral` to 1e-4),
   so that the renderer can normalise the lobe by a value filtered exactly as
   the map is.

The map is a (T, T, B) RGBA32F 3D texture, x ↔ paraboloid s, y ↔ t, z ↔
w = θ_v / π; arrays are (B, T, T, 4) in that upload order. On the GPU each step
is a compute pass (shaders/banks/rings.glsl, slices.glsl, OpenGL 4.3);
:func:`build_cpu` is the NumPy twin for tests and contexts without compute
shaders, with a progress bar.
"""

from __future__ import annotations

import contextlib
import math
import time
from dataclasses import dataclass

import moderngl
import numpy as np
import numpy.typing as npt
from tqdm import tqdm

from envstudio.core.resample import sample_cube
from envstudio.gpu.programs import ProgramLibrary
from envstudio.methods.banks import lobe as banks
from envstudio.plugin import PassTimer, set_uniform
from envstudio.prefilter.mip_chain import box_mip_chain

_GROUP = 8  # compute work-group edge (rings.glsl, slices.glsl)


@dataclass(frozen=True)
class MapSpec:
    """Resolution and BRDF of one 3D map.

    Attributes
    ----------
    size : int
        T, texels across the tangent face (a border of core.banks.BORDER included).
    slices : int
        B, slices in θ_v = ∠(v, t) ∈ [0°, 180°].
    bins : int
        K, ring bins in θ = ∠(l, t); M = 2K samples per ring.
    sharpness : float
        s ∈ [0, 1).
    """

    size: int = 64
    slices: int = 64
    bins: int = 128
    sharpness: float = 0.9

    def __post_init__(self):
        banks.lobe(0.0, 0.0, self.sharpness)  # validates s
        if self.size <= 2 * banks.BORDER or self.slices < 1 or self.bins < 2:
            raise ValueError(f"bad banks map resolution {self}")

    @property
    def ring_samples(self) -> int:
        """M, samples per ring: 2K, so their spacing 2π sin θ / M ≤ π / K, one bin."""
        return 2 * self.bins

    @property
    def map_bytes(self) -> int:
        """Bytes of the RGBA32F map: T² B · 16."""
        return self.size * self.size * self.slices * 16

    @property
    def ring_bytes(self) -> int:
        """Bytes of the RGBA32F ring table the GPU build keeps: T² K · 16."""
        return self.size * self.size * self.bins * 16


def ring_level(cube_size: int, bins: int) -> int:
    """The box mip level of a cube of ``cube_size`` whose texels are about one ring bin wide.

    A face texel of level L spans about (π/2) / (n / 2^L), a bin π / K; the level
    is round(log2(2n / K)), clamped to the chain.
    """
    top = int(math.log2(cube_size))
    return int(np.clip(round(math.log2(2.0 * cube_size / bins)), 0, top))


def build_cpu(
    faces: npt.ArrayLike, spec: MapSpec, progress: bool = True
) -> npt.NDArray[np.float32]:
    """The 3D map in NumPy from a cube map's level 0 (module docstring).

    Parameters
    ----------
    faces
        (6, n, n, 3) float, core.cubemap layout, linear radiance, n a power of two.
    spec
        Resolution and sharpness.
    progress
        Show a tqdm bar over the ring bins (on stderr).

    Returns
    -------
    (B, T, T, 4) float32
        RGB: L_banks, radiance (paper's normalisation 1/(1 − s)²); A: the map of
        a unit environment at that slice.
    """
    tangents = banks.texel_tangents(spec.size).reshape(-1, 3)
    rings = rings_cpu(faces, tangents, spec, progress)
    weights = banks.ring_weights(spec.slices, spec.bins, spec.sharpness)
    out = np.empty((spec.slices, len(tangents), 4), np.float32)
    out[..., :3] = np.einsum("jk,pkc->jpc", weights, rings)
    out[..., 3] = 2.0 * np.pi * weights.sum(axis=1)[:, None]
    return out.reshape(spec.slices, spec.size, spec.size, 4)


def rings_cpu(
    faces: npt.ArrayLike, tangents: npt.ArrayLike, spec: MapSpec, progress: bool = False
) -> npt.NDArray[np.float64]:
    """Pass 1 in NumPy: R_t(θ_k) for any unit tangents (module docstring).

    Parameters
    ----------
    faces
        (6, n, n, 3) float cube map level 0, n a power of two.
    tangents
        (P, 3) float unit tangents.
    spec
        K (bins) and M (ring samples); the level read is :func:`ring_level`'s.
    progress
        Show a tqdm bar over the bins.

    Returns
    -------
    (P, K, 3) float64
        Radiance integrated over φ around each ring, W/(m² sr) · rad.
    """
    chain = box_mip_chain(np.asarray(faces, np.float64)[..., :3])
    level = chain[ring_level(chain[0].shape[1], spec.bins)]
    tangents = np.asarray(tangents, np.float64).reshape(-1, 3)
    rings = np.empty((len(tangents), spec.bins, 3))
    scale = 2.0 * np.pi / spec.ring_samples
    angles = banks.bin_angles(spec.bins)
    for k in tqdm(range(spec.bins), desc="banks rings", unit="bin", disable=not progress):
        directions = banks.ring_directions(tangents, angles[k], spec.ring_samples)
        rings[:, k] = sample_cube(level, directions).sum(axis=1, dtype=np.float64) * scale
    return rings


def map_texture(ctx: moderngl.Context, spec: MapSpec) -> moderngl.Texture3D:
    """An empty (T, T, B) RGBA32F 3D texture, trilinear, clamped (θ_v ends at 0° and 180°)."""
    texture = ctx.texture3d((spec.size, spec.size, spec.slices), 4, dtype="f4")
    texture.filter = (moderngl.LINEAR, moderngl.LINEAR)
    texture.repeat_x = texture.repeat_y = texture.repeat_z = False
    return texture


def upload(
    ctx: moderngl.Context, spec: MapSpec, values: npt.NDArray[np.float32]
) -> moderngl.Texture3D:
    """A :func:`map_texture` holding ``values``, (B, T, T, 4) float32 (:func:`build_cpu`)."""
    texture = map_texture(ctx, spec)
    texture.write(np.ascontiguousarray(values, np.float32).tobytes())
    return texture


def read_map(texture: moderngl.Texture3D) -> npt.NDArray[np.float32]:
    """(B, T, T, 4) float32 contents of a map texture."""
    w, h, d = texture.size
    return np.frombuffer(texture.read(), np.float32).reshape(d, h, w, 4).copy()


class GpuMapBuilder:
    """The two compute passes of the module docstring; owns the ring table and weights.

    Parameters
    ----------
    ctx, programs
        Context (OpenGL 4.3 or later) and its program cache.
    """

    def __init__(self, ctx: moderngl.Context, programs: ProgramLibrary):
        self.ctx = ctx
        self.programs = programs
        self._rings: moderngl.Texture3D | None = None
        self._weights: moderngl.Texture | None = None
        self._weights_key: tuple | None = None
        #: Wall-clock seconds of the last build (both passes, ctx.finish() included).
        self.last_build_s = 0.0

    def build(
        self,
        cube: moderngl.TextureCube,
        spec: MapSpec,
        target: moderngl.Texture3D,
        timer: PassTimer | None = None,
        rings_valid: bool = False,
    ) -> None:
        """Fill ``target`` (:func:`map_texture` of ``spec``) from ``cube``.

        Parameters
        ----------
        cube
            The static environment, RGBA32F with its mip chain.
        spec
            Resolution and sharpness.
        target
            The map to write.
        timer
            Where the passes ``banks.rings`` and ``banks.slices`` are reported.
        rings_valid
            The ring table already holds this cube at this size and bin count
            (only s changed): skip pass 1.
        """
        start = time.perf_counter()
        rings_shape = (spec.size, spec.size, spec.bins)
        if self._rings is None or self._rings.size != rings_shape:
            self._release_rings()
            self._rings = self.ctx.texture3d(rings_shape, 4, dtype="f4")
            rings_valid = False
        if not rings_valid:
            program = self.programs.compute("banks/rings.glsl")
            cube.use(location=0)
            set_uniform(program, "u_environment", 0)
            set_uniform(program, "u_lod", float(ring_level(cube.size[0], spec.bins)))
            set_uniform(program, "u_border", float(banks.BORDER))
            set_uniform(program, "u_ring_samples", spec.ring_samples)
            self._rings.bind_to_image(0, read=False, write=True)
            with _measure(timer, "banks.rings"):
                program.run(_groups(spec.size), _groups(spec.size), spec.bins)
                self.ctx.memory_barrier(moderngl.ALL_BARRIER_BITS)
        program = self.programs.compute("banks/slices.glsl")
        self._weight_table(spec).use(location=1)
        set_uniform(program, "u_weights", 1)
        self._rings.bind_to_image(0, read=True, write=False)
        target.bind_to_image(1, read=False, write=True)
        with _measure(timer, "banks.slices"):
            program.run(_groups(spec.size), _groups(spec.size), spec.slices)
            self.ctx.memory_barrier(moderngl.ALL_BARRIER_BITS)
        self.ctx.finish()
        self.last_build_s = time.perf_counter() - start

    def _weight_table(self, spec: MapSpec) -> moderngl.Texture:
        """(K × B) R32F texture of the ring weights w_k(θ_v,j), rebuilt when s or B, K change."""
        key = (spec.slices, spec.bins, spec.sharpness)
        if key != self._weights_key:
            if self._weights is not None:
                self._weights.release()
            weights = banks.ring_weights(spec.slices, spec.bins, spec.sharpness)
            data = np.ascontiguousarray(weights, np.float32)
            self._weights = self.ctx.texture(
                (spec.bins, spec.slices), 1, data.tobytes(), dtype="f4"
            )
            self._weights.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self._weights_key = key
        return self._weights

    def _release_rings(self) -> None:
        if self._rings is not None:
            self._rings.release()
        self._rings = None

    def release(self) -> None:
        """Free the ring table and the weights; safe to call twice."""
        self._release_rings()
        if self._weights is not None:
            self._weights.release()
        self._weights = None
        self._weights_key = None


def _groups(n: int) -> int:
    return (n + _GROUP - 1) // _GROUP


def _measure(timer: PassTimer | None, name: str):
    return timer.measure(name) if timer is not None else contextlib.nullcontext()
