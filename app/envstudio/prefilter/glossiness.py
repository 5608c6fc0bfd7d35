"""Glossiness matching: LOD bias b of a box-filtered cube mip chain ↔ Phong exponent N.

Seed 000 replaces the Phong prefilter of its eq. 7 (§3.2), L(r) = (N+1)/2π ∫
max(r·l, 0)^N L(l) dl, by a box-filtered cube mip chain read at LOD bias b
(§4.2, §5.2), and Figure 5 shows N = 225 (the hardware prefilter of Kautz et
al.) beside b = 2.25 as "comparable glossiness" (§6), without saying how the
two were matched or how large the cube was. Here the match is a fitted, stored
function, so that switching methods (``compare``, the UI's glossiness toggle)
keeps the look.

The fit
    For each environment, cube size n and exponent N, ℓ*(N, n) is the mip level
    at which the trilinear box-chain lookup (prefilter.mip_chain) best
    reproduces prefilter.brute_force.phong over a Fibonacci set of reflection
    directions, measured as the mean squared difference of log(Y + ε), Y the
    Rec. 709 luminance and ε 1 % of its mean. Luminance, because glossiness is
    a blur of the picture, not of its colours; a log domain, because in linear
    radiance the few directions beside a sun (10⁴–10⁵ × the mean in the shipped
    maps) decide the whole sum, while what one judges on the screen is the
    tone-mapped shape of every highlight and edge. Points whose ℓ* lies below
    ½ or above log2(n) − 1.5 are left out: there GL's clamp of the level to
    [0, log2 n], or the six face means of the top levels (seed 000 Figure 4),
    decide the look rather than the match.

The model
    A level is a blur 2^ℓ texels wide, a texel about 1/n of a face, and a Phong
    lobe about N^−½ radians wide, so a blur of 2^u texels with

        u = a + c·log2(n) + d·log2(N)

    should match, with c = 1 and d = −½. The trilinear blend between two levels
    is not a blur of intermediate width, though: its variance grows linearly in
    the blend factor (:func:`trilinear_level`), so the level is b = W(u) with
    W(u) = ⌊u⌋ + (4^{u−⌊u⌋} − 1)/3. Without W the fitted ℓ* scatter about a
    straight line in log2(N) with a period of one level. a, c and d are fitted
    by nonlinear least squares on ℓ*, started from the linear fit of W⁻¹(ℓ*).
    The data give c = 1 (a cube twice as large needs exactly one level more)
    and a d a little flatter than −½.

The stored fit (:data:`DATA_FILE`, written by ``envstudio fit-glossiness``)
holds the coefficients, the residual, the settings and every ℓ*. Both
directions of the mapping ignore GL's clamp: b is a bias to which the base LOD
of a real draw (from screen-space derivatives, negative when magnified) is
added, and the two functions are exact inverses over the whole real line.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np
import numpy.typing as npt
from scipy.optimize import least_squares, minimize_scalar

from envstudio.core.env_sampling import luminance
from envstudio.core.resample import latlong_to_cube
from envstudio.prefilter.brute_force import downsample_latlong, phong
from envstudio.prefilter.mip_chain import box_mip_chain, level_samples, trilinear

__all__ = [
    "DATA_FILE",
    "DEFAULT_DIRECTIONS",
    "DEFAULT_EXPONENTS",
    "DEFAULT_SIZES",
    "FIT_ENVIRONMENTS",
    "GlossinessModel",
    "best_level",
    "blur_octaves",
    "exponent_for_lod_bias",
    "fibonacci_directions",
    "fit_glossiness",
    "level_error",
    "load_model",
    "lod_bias_for_exponent",
    "phong_reference",
    "reference_height",
    "trilinear_level",
]

#: The stored fit, package data of ``envstudio`` (also in a source checkout).
DATA_FILE = Path(__file__).resolve().parents[1] / "data" / "glossiness_fit.json"
#: Shipped environments the stored fit uses; interior, studio and sunrise are held out.
FIT_ENVIRONMENTS = ("city", "courtyard", "forest", "night", "sunset")
#: Cube face sizes n of the stored fit.
DEFAULT_SIZES = (64, 128, 256, 512)
#: Exponents N of the stored fit: 2 … 2048, half an octave apart.
DEFAULT_EXPONENTS = tuple(float(2.0 ** (k / 2)) for k in range(2, 23))
#: Reflection directions per environment.
DEFAULT_DIRECTIONS = 512

# ε of the log domain, relative to the mean luminance of the reference.
_LOG_FLOOR = 0.01
# Lat-long texel edge of the reference at most this fraction of the lobe width N^−½.
_TEXEL_PER_LOBE = 0.6
_MIN_REFERENCE_HEIGHT = 64
# Reference queries per brute-force call, so that one call holds about 2^24 texel pairs.
_PAIRS_PER_CALL = 2**24
# Grid step of the level search before the bounded refinement.
_LEVEL_STEP = 1.0 / 32.0
# Points kept for the model: ℓ* in [_LOW, log2(n) − _HIGH].
_LOW, _HIGH = 0.5, 1.5


@dataclass(frozen=True)
class GlossinessModel:
    """The fitted map b = W(a + c·log2(n) + d·log2(N)) (module docstring).

    Attributes
    ----------
    a, c, d
        Coefficients; d < 0, so b grows as N falls.
    residual_rms
        Root-mean-square of ℓ* − b over the points fitted, in mip levels.
    """

    a: float
    c: float
    d: float
    residual_rms: float

    def __post_init__(self):
        if not self.d < 0.0:
            raise ValueError(f"glossiness model needs d < 0 (b falls as N grows), got d = {self.d}")

    def lod_bias(self, exponent: npt.ArrayLike, cube_size: npt.ArrayLike) -> np.ndarray:
        """b for Phong exponents N > 0 and cube face sizes n > 0 (broadcast)."""
        N = _positive(exponent, "Phong exponent")
        n = _positive(cube_size, "cube size")
        return trilinear_level(self.a + self.c * np.log2(n) + self.d * np.log2(N))

    def exponent(self, lod_bias: npt.ArrayLike, cube_size: npt.ArrayLike) -> np.ndarray:
        """N for LOD biases b and cube face sizes n > 0 (broadcast); inverse of :meth:`lod_bias`."""
        u = blur_octaves(lod_bias)
        n = _positive(cube_size, "cube size")
        return np.exp2((u - self.a - self.c * np.log2(n)) / self.d)


def trilinear_level(octaves: npt.ArrayLike) -> np.ndarray:
    """The mip level ℓ = W(u) whose trilinear blend has the blur width 2^u.

    Level k of a box chain has a kernel variance (per axis, in level-0 texels²)
    of 4^k/12 for its 2^k-texel box plus 4^k/6 for its bilinear tent, 4^k·σ₀²
    with σ₀² = ¼; the trilinear blend (1 − f)·level k + f·level k+1 has the variance
    (1 − f)·4^k σ₀² + f·4^{k+1} σ₀² = 4^k (1 + 3f) σ₀², so a blur of width 2^u
    (variance 4^u σ₀²) is reached at k = ⌊u⌋, f = (4^{u−k} − 1)/3. W is
    continuous and increasing, with W(k) = k at every integer.

    Parameters
    ----------
    octaves
        u, any shape.

    Returns
    -------
    ndarray of float64
        ℓ, same shape.
    """
    u = np.asarray(octaves, dtype=np.float64)
    k = np.floor(u)
    return k + (np.exp2(2.0 * (u - k)) - 1.0) / 3.0


def blur_octaves(level: npt.ArrayLike) -> np.ndarray:
    """u = W⁻¹(ℓ) = ⌊ℓ⌋ + log4(1 + 3(ℓ − ⌊ℓ⌋)), the inverse of :func:`trilinear_level`."""
    level = np.asarray(level, dtype=np.float64)
    k = np.floor(level)
    return k + 0.5 * np.log2(1.0 + 3.0 * (level - k))


@cache
def load_model(path: str | os.PathLike | None = None) -> GlossinessModel:
    """Read a fit written by ``envstudio fit-glossiness``.

    Parameters
    ----------
    path
        JSON file; default :data:`DATA_FILE`.

    Returns
    -------
    GlossinessModel
    """
    model = json.loads(Path(path or DATA_FILE).read_text(encoding="utf-8"))["model"]
    coefficients = model["coefficients"]
    return GlossinessModel(
        coefficients["a"], coefficients["c"], coefficients["d"], model["residual_rms"]
    )


def lod_bias_for_exponent(N: npt.ArrayLike, cube_size: npt.ArrayLike) -> np.ndarray:
    """LOD bias b of a box-filtered cube mip chain that looks like Phong exponent N.

    Parameters
    ----------
    N
        Phong exponent(s) of seed 000 eq. 7, > 0, any shape.
    cube_size
        Face edge n in texels of the cube map the bias is applied to, broadcast against N.

    Returns
    -------
    ndarray of float64
        b in mip levels, broadcast shape; not clamped to [0, log2 n] (module docstring).
    """
    return load_model().lod_bias(N, cube_size)


def exponent_for_lod_bias(b: npt.ArrayLike, cube_size: npt.ArrayLike) -> np.ndarray:
    """Phong exponent N that looks like a box-filtered cube mip chain read at LOD bias b.

    Parameters
    ----------
    b
        LOD bias(es) in mip levels, any real value, any shape.
    cube_size
        Face edge n in texels, broadcast against b.

    Returns
    -------
    ndarray of float64
        N > 0, broadcast shape; the inverse of :func:`lod_bias_for_exponent`.
    """
    return load_model().exponent(b, cube_size)


def fibonacci_directions(count: int) -> npt.NDArray[np.float64]:
    """Nearly uniform unit directions (a Fibonacci lattice on the sphere).

    Returns
    -------
    (count, 3) float64
        Point i at height y = 1 − (2i + 1)/count, turned by the golden angle per step.
    """
    i = np.arange(count) + 0.5
    y = 1.0 - 2.0 * i / count
    r = np.sqrt(1.0 - y * y)
    phi = np.pi * (1.0 + math.sqrt(5.0)) * i
    return np.stack([r * np.cos(phi), y, r * np.sin(phi)], axis=-1)


def reference_height(exponent: float, source_height: int) -> int:
    """Lat-long height at which the brute-force Phong reference resolves the lobe.

    The smallest power of two h ≥ 64 whose texel edge π/h is at most 0.6 of the lobe
    width N^−½ (cos^N θ ≈ exp(−Nθ²/2)), capped at the source height; the box
    downsampling to h then adds at most 3 % to the lobe's variance.
    """
    height = _MIN_REFERENCE_HEIGHT
    while height < source_height and math.pi / height > _TEXEL_PER_LOBE / math.sqrt(exponent):
        height *= 2
    return min(height, source_height)


def phong_reference(
    image: npt.ArrayLike, directions: npt.ArrayLike, exponent: float
) -> npt.NDArray[np.float64]:
    """Luminance of the brute-force Phong prefilter (seed 000 eq. 7, normalised).

    Parameters
    ----------
    image
        (h, 2h, 3) float, lat-long linear radiance; box-downsampled to
        :func:`reference_height` first (h must be a power of two ≥ 64).
    directions
        (m, 3) float, unit reflection directions.
    exponent
        N.

    Returns
    -------
    (m,) float64
        Rec. 709 luminance of prefilter.brute_force.phong.
    """
    image = np.asarray(image, dtype=np.float64)
    small = downsample_latlong(image, reference_height(exponent, image.shape[0]))
    step = max(1, _PAIRS_PER_CALL // (small.shape[0] * small.shape[1]))
    directions = np.asarray(directions, dtype=np.float64)
    parts = [
        phong(small, directions[start : start + step], exponent)
        for start in range(0, len(directions), step)
    ]
    return luminance(np.concatenate(parts))


def level_error(
    samples: npt.ArrayLike, reference: npt.ArrayLike, levels: npt.ArrayLike
) -> npt.NDArray[np.float64]:
    """Mean squared log-luminance error of the trilinear lookup at each level.

    Parameters
    ----------
    samples
        (L + 1, m) float, luminance of prefilter.mip_chain.level_samples.
    reference
        (m,) float, luminance of the Phong reference in the same directions.
    levels
        (k,) float, mip levels ℓ.

    Returns
    -------
    (k,) float64
        mean over directions of (log(Y(ℓ) + ε) − log(Y_ref + ε))², ε = 1 % of mean Y_ref.
    """
    samples = np.asarray(samples, dtype=np.float64)
    reference = np.asarray(reference, dtype=np.float64)
    eps = _LOG_FLOOR * reference.mean()
    levels = np.atleast_1d(np.asarray(levels, dtype=np.float64))
    shape = (len(samples), len(levels), len(reference), 1)
    stacked = np.broadcast_to(samples[:, None, :, None], shape)
    lookup = trilinear(stacked, levels[:, None])[..., 0]
    return np.mean((np.log(lookup + eps) - np.log(reference + eps)) ** 2, axis=-1)


def best_level(samples: npt.ArrayLike, reference: npt.ArrayLike) -> float:
    """The mip level ℓ* in [0, L] minimising :func:`level_error`.

    A search on a grid of 1/32 level, then a bounded scalar minimisation within one
    grid step of the best grid point.
    """
    samples = np.asarray(samples, dtype=np.float64)
    top = samples.shape[0] - 1
    grid = np.arange(0.0, top + _LEVEL_STEP / 2, _LEVEL_STEP)
    start = grid[np.argmin(level_error(samples, reference, grid))]
    bounds = (max(start - _LEVEL_STEP, 0.0), min(start + _LEVEL_STEP, top))
    result = minimize_scalar(
        lambda level: level_error(samples, reference, level)[0],
        bounds=bounds,
        method="bounded",
        options={"xatol": 1e-4},
    )
    return float(result.x)


def fit_glossiness(
    environments: Mapping[str, npt.ArrayLike],
    sizes: Sequence[int] = DEFAULT_SIZES,
    exponents: Sequence[float] = DEFAULT_EXPONENTS,
    directions: int = DEFAULT_DIRECTIONS,
    progress: Callable[[int, int], None] | None = None,
) -> dict:
    """Fit the glossiness model (module docstring) to lat-long environments.

    Parameters
    ----------
    environments
        Name → (h, 2h, 3) float lat-long linear radiance, h a power of two ≥ 64.
    sizes
        Cube face sizes n (powers of two).
    exponents
        Phong exponents N > 0.
    directions
        Number of Fibonacci reflection directions per environment.
    progress
        Called as ``progress(done, total)`` after each cube and each reference.

    Returns
    -------
    dict
        JSON-ready: ``model`` (formula, coefficients a, c, d, residual_rms,
        residual_max, points_used), ``settings`` and ``levels`` (environment →
        ℓ*, a list per size of a value per exponent).
    """
    dirs = fibonacci_directions(directions)
    total = len(environments) * (len(sizes) + len(exponents))
    done = 0
    levels = {}
    for name, image in environments.items():
        samples = []
        for n in sizes:
            samples.append(luminance(level_samples(box_mip_chain(latlong_to_cube(image, n)), dirs)))
            done += 1
            if progress:
                progress(done, total)
        table = np.empty((len(sizes), len(exponents)))
        for j, N in enumerate(exponents):
            reference = phong_reference(image, dirs, N)
            table[:, j] = [best_level(s, reference) for s in samples]
            done += 1
            if progress:
                progress(done, total)
        levels[name] = table
    return {
        "model": _fit_model(levels, sizes, exponents),
        "settings": {
            "environments": list(environments),
            "sizes": [int(n) for n in sizes],
            "exponents": [float(N) for N in exponents],
            "directions": int(directions),
            "error": "mean squared difference of log(Y + 0.01 mean Y), Y = Rec. 709 luminance",
            "lookup": "trilinear; seamless bilinear per level; box mip chain per face",
            "reference": "prefilter.brute_force.phong on a lat-long with texel <= 0.6 N^-1/2",
            "kept": f"{_LOW} <= level <= log2(n) - {_HIGH}",
        },
        "levels": {name: np.round(t, 4).tolist() for name, t in levels.items()},
    }


def _fit_model(
    levels: Mapping[str, np.ndarray], sizes: Sequence[int], exponents: Sequence[float]
) -> dict:
    """Least-squares a, c, d of b = W(a + c·log2 n + d·log2 N) on the kept ℓ*."""
    stacked = np.stack(list(levels.values()))
    log_n, log_N = np.meshgrid(np.log2(sizes), np.log2(exponents), indexing="ij")
    log_n, log_N = np.broadcast_to(log_n, stacked.shape), np.broadcast_to(log_N, stacked.shape)
    kept = (stacked >= _LOW) & (stacked <= log_n - _HIGH)
    if kept.sum() < 3:
        raise ValueError(f"only {kept.sum()} fitted levels inside the model's range; need 3")
    design = np.stack([np.ones(kept.sum()), log_n[kept], log_N[kept]], axis=-1)
    target = stacked[kept]
    start, *_ = np.linalg.lstsq(design, blur_octaves(target), rcond=None)
    coefficients = least_squares(lambda x: trilinear_level(design @ x) - target, start).x
    residual = trilinear_level(design @ coefficients) - target
    a, c, d = (float(x) for x in coefficients)
    return {
        "formula": "b = W(a + c*log2(n) + d*log2(N)), W(u) = floor(u) + (4^(u - floor(u)) - 1)/3",
        "coefficients": {"a": a, "c": c, "d": d},
        "residual_rms": float(np.sqrt(np.mean(residual**2))),
        "residual_max": float(np.abs(residual).max()),
        "points_used": int(kept.sum()),
    }


def _positive(values: npt.ArrayLike, name: str) -> np.ndarray:
    array = np.asarray(values, dtype=np.float64)
    if np.any(~(array > 0.0)):
        raise ValueError(f"{name} must be positive, got {values!r}")
    return array
