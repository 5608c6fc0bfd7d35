"""Diffuse lighting as SH plus extracted lights: seed 000 section 4.1 and past it.

Seed 000 represents the irradiance of an environment by its 9 SH coefficients
(eq. 9–12). On environments dominated by small bright sources (a sun, lamps) the
truncated series rings: on the shipped maps (256 × 128, 2000 random normals,
luminance; ``envstudio sh --height 128 --check``) its mean relative irradiance
error is 1.6 % (sunset) to 26 % (sunrise) and its maximum up to 214 %. This
module splits the environment first::

    L(l) = L_res(l) + Σ_k L_k(l)

- the threshold T = τ · mean luminance (mean over the sphere, Σ lum Δω / 4π);
- every sample brighter than T gives up its *excess* L · (1 − T / lum), keeping
  its chromaticity, so the rest never exceeds T;
- the excess is grouped by cube-face tiles (``tiles_per_edge``² per face, 8² by
  default, ≈ 11° wide); the K tiles of largest excess power become lights, the
  excess of the other tiles stays in the residual;
- the residual is projected into SH (core.sh_bands, eq. 11) and convolved with
  the clamped cosine (eq. 12); each light is a uniform spherical cap with the
  tile's excess power P, its vector moment V = Σ lum Δω l (luminance) and its
  colour, whose irradiance is evaluated exactly (Snyder 1996, the closed form
  for a sphere light, :func:`cap_irradiance`).

A cap of half-angle α and radiance L_c has power P = 2π L_c (1 − cos α) and
moment |V| = π L_c sin²α, so cos α = 2|V|/P − 1; while it is wholly above the
horizon of n its irradiance is n·V, exactly what the tile gives, so the cap
only approximates the tile's shape where it straddles the horizon.
With τ = 1, K = 32 and the residual at order 6 (``BAND_SETS[49]``) the mean
relative irradiance error is at most 0.18 % and the maximum at most 6.2 % on
all eight shipped maps (studies/kautz-border-and-sun/README.md, which also gives the settings
that were measured and rejected). shaders/prefilter/sh_project.glsl and reduce.glsl
compute the same decomposition on the GPU from a cube map.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from envstudio.core import cubemap, latlong
from envstudio.core.env_sampling import luminance
from envstudio.core.latlong import _as_vectors
from envstudio.core.sh_bands import BAND_SETS, a_hat, band_indices, sh_basis

__all__ = [
    "MAX_SIN2_ALPHA",
    "DiffuseLighting",
    "DiffuseProjector",
    "cap_irradiance",
    "cube_tiles",
]

#: Caps are kept below a half-angle of 84° (sin²α ≤ 0.99): the closed form divides by cot α.
MAX_SIN2_ALPHA = 0.99

#: A sample is above the threshold when brighter than T by more than rounding (a constant
#: map, whose every sample equals its mean, has no excess).
_MARGIN = 1.0 + 1e-4

#: Samples per product of :meth:`DiffuseProjector._quadrature`.
_CHUNK = 4096

#: Below this sin²α a light is a directional light (max(n·l, 0)).
_POINT_SIN2 = 1e-6


def cube_tiles(directions: npt.ArrayLike, per_edge: int) -> npt.NDArray[np.int64]:
    """Cube-face tile of each direction.

    Parameters
    ----------
    directions
        (..., 3) float, non-zero.
    per_edge
        Tiles along a face edge.

    Returns
    -------
    (...) int64
        face · per_edge² + row · per_edge + column, with row ↔ t and column ↔ s
        (core.cubemap face layout), in 0 … 6 · per_edge² − 1.
    """
    face, uv = cubemap.direction_to_uv(directions)
    cell = np.minimum((uv * per_edge).astype(np.int64), per_edge - 1)
    return (face * per_edge + cell[..., 1]) * per_edge + cell[..., 0]


def cap_irradiance(cos_theta: npt.ArrayLike, sin2_alpha: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Irradiance of a uniform spherical cap relative to a directional light of equal moment.

    For a cap of half-angle α whose centre makes the angle θ with the normal,
    Snyder's closed form ("Area light sources for real-time graphics", 1996) is
    E / L_c = π sin²α cos θ when the cap is wholly above the horizon
    (cos²θ ≥ sin²α, cos θ > 0) and otherwise, with x = cot α and
    y = −x cot θ, (cos θ acos y − x sin θ sqrt(1 − y²)) sin²α
    + atan(sin θ sqrt(1 − y²) / x). Divided by π sin²α (the moment |V| / L_c)
    it is max(cos θ, 0) away from the horizon, and falls smoothly to 0 at
    θ = π/2 + α. shaders/common/cap_light.glsl is the GLSL twin.

    Parameters
    ----------
    cos_theta
        (...) float, cosine between the normal and the cap's centre.
    sin2_alpha
        (...) float, sin² of the half-angle, in [0, MAX_SIN2_ALPHA].

    Returns
    -------
    (...) float64
        E / |V| in [0, 1]; multiply by the light's moment.
    """
    c = np.clip(np.asarray(cos_theta, dtype=np.float64), -1.0, 1.0)
    s2 = np.broadcast_to(np.asarray(sin2_alpha, dtype=np.float64), c.shape)
    outside = (c * c >= s2) | (s2 < _POINT_SIN2)
    safe_s2 = np.where(outside, 0.5, s2)
    sin_theta = np.sqrt(np.maximum(1.0 - c * c, 1e-12))
    x = np.sqrt(1.0 / safe_s2 - 1.0)
    y = np.clip(-x * c / sin_theta, -1.0, 1.0)
    root = sin_theta * np.sqrt(1.0 - y * y)
    partial = ((c * np.arccos(y) - x * root) * safe_s2 + np.arctan(root / x)) / (np.pi * safe_s2)
    return np.where(outside, np.maximum(c, 0.0), np.maximum(partial, 0.0))


@dataclass(frozen=True)
class DiffuseLighting:
    """Residual SH coefficients plus cap lights: what the kautz shaders evaluate.

    Attributes
    ----------
    bands : tuple of int
        Band set of the coefficients (core.sh_bands).
    coefficients : (n, 3) float64
        L_i of the residual environment (seed 000 eq. 11), storage order.
    lights : (k, 7) float64
        Per light: unit direction (3), sin²α (1), and the RGB moment magnitude
        |V| · P_rgb / P (3), in order of decreasing power.
    """

    bands: tuple[int, ...]
    coefficients: npt.NDArray[np.float64]
    lights: npt.NDArray[np.float64]

    def irradiance(self, normals: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """E(n): eq. 12 on the residual plus the caps.

        Parameters
        ----------
        normals
            (..., 3) float, unit normals.

        Returns
        -------
        (..., 3) float64
            Irradiance; the diffuse radiance is k_d / π times it.
        """
        n = _as_vectors(normals, 3, "normals")
        e = sh_basis(n, self.bands) @ self.convolved()
        for light in self.lights:
            e = e + cap_irradiance(n @ light[:3], light[3])[..., None] * light[4:7]
        return e

    def convolved(self) -> npt.NDArray[np.float64]:
        """(n, 3) Â_l L_i: the coefficients the shaders dot with Y_i(n)."""
        degree, _ = band_indices(self.bands)
        return np.array([a_hat(int(b)) for b in degree])[:, None] * self.coefficients

    def block(self, light_slots: int) -> npt.NDArray[np.float32]:
        """The uniform block of shaders/common/sh_irradiance.glsl as rows of vec4.

        Parameters
        ----------
        light_slots
            Light array length of the shader (unused slots are zero: no light).

        Returns
        -------
        (n + 2 · light_slots, 4) float32
            ``vec4(Â L_i, 0)`` per coefficient, then ``vec4(direction, sin²α)``
            and ``vec4(rgb, 0)`` per slot (std140 and std430 agree for vec4 arrays).
        """
        if len(self.lights) > light_slots:
            raise ValueError(f"{len(self.lights)} lights do not fit {light_slots} slots")
        n = len(self.coefficients)
        rows = np.zeros((n + 2 * light_slots, 4), dtype=np.float32)
        rows[:n, :3] = self.convolved()
        k = len(self.lights)
        rows[n : n + k, :4] = self.lights[:, :4]
        rows[n + light_slots : n + light_slots + k, :3] = self.lights[:, 4:7]
        return rows


class DiffuseProjector:
    """Quadrature of one sample set (lat-long or cube texels), precomputed once.

    ``project`` is then a threshold, a few bincounts and one matrix product:
    the basis times the solid angles is kept as an (N, n) matrix.

    Parameters
    ----------
    directions
        (..., 3) float, unit sample directions.
    solid_angles
        (...) float, steradians per sample (exact texel solid angles).
    coefficients
        9, 25 or 49: the band set ``BAND_SETS[coefficients]`` of the residual.
    lights
        K, the number of extracted cap lights (0: plain projection, the seed's).
    threshold
        τ: samples brighter than τ × mean luminance give up their excess.
    tiles_per_edge
        Excess tiles along a cube face edge.
    """

    def __init__(
        self,
        directions: npt.ArrayLike,
        solid_angles: npt.ArrayLike,
        coefficients: int = 9,
        lights: int = 0,
        threshold: float = 1.0,
        tiles_per_edge: int = 8,
    ):
        if coefficients not in BAND_SETS:
            raise ValueError(f"coefficients must be one of {sorted(BAND_SETS)}, got {coefficients}")
        if lights < 0 or threshold <= 0.0 or tiles_per_edge < 1:
            raise ValueError("lights must be >= 0, threshold > 0 and tiles_per_edge >= 1")
        self.bands = BAND_SETS[coefficients]
        self.lights = int(lights)
        self.threshold = float(threshold)
        self.tiles = 6 * tiles_per_edge**2
        self._directions = _as_vectors(directions, 3, "directions").reshape(-1, 3)
        self._weights = np.asarray(solid_angles, dtype=np.float64).reshape(-1)
        if len(self._weights) != len(self._directions):
            raise ValueError(
                f"{len(self._directions)} directions but {len(self._weights)} solid angles"
            )
        self._weighted_basis = sh_basis(self._directions, self.bands) * self._weights[:, None]
        self._tile = cube_tiles(self._directions, tiles_per_edge)

    @classmethod
    def for_latlong(cls, height: int, width: int | None = None, **options) -> DiffuseProjector:
        """Projector of an (h, w) lat-long map (core.latlong layout, row 0 = +Y)."""
        return cls(
            latlong.texel_directions(height, width),
            latlong.texel_solid_angles(height, width),
            **options,
        )

    @classmethod
    def for_cube(cls, size: int, **options) -> DiffuseProjector:
        """Projector of a (6, n, n) cube map (core.cubemap layout)."""
        return cls(cubemap.texel_directions(size), cubemap.texel_solid_angles(size), **options)

    def _quadrature(self, radiance: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """(n, 3) Σ_k L_k Y_i(d_k) Δω_k.

        As (3, N) @ (N, n) products over chunks of samples: each is small enough for BLAS
        to run on one thread (a whole 6 × 64² product threaded by OpenBLAS took 14 ms on
        a busy two-core machine against 0.6 ms in chunks).
        """
        rows = np.ascontiguousarray(radiance.T)
        total = np.zeros((3, self._weighted_basis.shape[1]))
        for start in range(0, rows.shape[1], _CHUNK):
            total += rows[:, start : start + _CHUNK] @ self._weighted_basis[start : start + _CHUNK]
        return total.T

    def project(self, radiance: npt.ArrayLike) -> DiffuseLighting:
        """Decompose and project one environment (module docstring).

        Parameters
        ----------
        radiance
            (..., 3) float, linear RGB per sample, in the layout of the directions.

        Returns
        -------
        DiffuseLighting
        """
        L = _as_vectors(radiance, 3, "radiance").reshape(-1, 3)
        if len(L) != len(self._weights):
            raise ValueError(f"expected {len(self._weights)} radiance samples, got {len(L)}")
        if self.lights == 0:
            coefficients = self._quadrature(L)
            return DiffuseLighting(self.bands, coefficients, np.zeros((0, 7)))
        lum = luminance(L)
        cutoff = self.threshold * (lum @ self._weights) / (4.0 * np.pi)
        above = lum > cutoff * _MARGIN
        fraction = np.where(above, 1.0 - cutoff / np.where(above, lum, 1.0), 0.0)
        excess = L * fraction[:, None]
        w = lum * fraction * self._weights

        def tile_sums(values: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
            return np.bincount(self._tile, values, minlength=self.tiles)

        power = tile_sums(w)
        chosen = np.array(
            [t for t in np.argsort(-power, kind="stable")[: self.lights] if power[t] > 0.0],
            dtype=np.int64,
        )
        selected = np.isin(self._tile, chosen)
        coefficients = self._quadrature(L - excess * selected[:, None])
        moment = np.stack([tile_sums(w * self._directions[:, i]) for i in range(3)], -1)[chosen]
        rgb = np.stack([tile_sums(excess[:, i] * self._weights) for i in range(3)], -1)[chosen]
        power = power[chosen]
        magnitude = np.linalg.norm(moment, axis=-1)
        cos_alpha = np.clip(2.0 * magnitude / power - 1.0, 0.0, 1.0)
        sin2 = np.minimum(1.0 - cos_alpha * cos_alpha, MAX_SIN2_ALPHA)
        lights = np.concatenate(
            [
                moment / magnitude[:, None],
                sin2[:, None],
                rgb * (magnitude / power)[:, None],
            ],
            axis=-1,
        )
        return DiffuseLighting(self.bands, coefficients, lights)
