"""Brute-force integrals of a lat-long environment: the independent references.

Every function sums over all texels of a (downsampled) lat-long map with their
exact solid angles (core.latlong.texel_solid_angles), in chunks so memory stays
bounded. They are slow and simple on purpose: tests and the glossiness fit
compare the GPU estimators and the hardware approximations against them.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.core import latlong
from envstudio.core.env_sampling import box_downsample

_CHUNK = 2048


def downsample_latlong(image: npt.ArrayLike, height: int) -> npt.NDArray[np.float64]:
    """Box-filter an (h, 2h, 3) map to (height, 2·height, 3); h must be a multiple of height."""
    img = np.asarray(image, dtype=np.float64)
    if img.shape[0] % height:
        raise ValueError(f"map height {img.shape[0]} is not a multiple of {height}")
    factor = img.shape[0] // height
    return box_downsample(img, factor) if factor > 1 else img


def _texels(image: npt.ArrayLike):
    img = np.asarray(image, dtype=np.float64)
    h, w = img.shape[:2]
    dirs = latlong.texel_directions(h, w).reshape(-1, 3)
    weighted = img.reshape(-1, 3) * latlong.texel_solid_angles(h, w).reshape(-1, 1)
    return dirs, weighted


def _kernel_sum(image, queries, kernel) -> npt.NDArray[np.float64]:
    dirs, weighted = _texels(image)
    q = np.asarray(queries, dtype=np.float64)
    flat = q.reshape(-1, 3)
    out = np.empty((len(flat), 3))
    for start in range(0, len(flat), _CHUNK):
        cos = flat[start : start + _CHUNK] @ dirs.T
        out[start : start + _CHUNK] = kernel(cos) @ weighted
    return out.reshape(*q.shape[:-1], 3)


def irradiance(image: npt.ArrayLike, normals: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """E(n) = ∫ L(l) max(n·l, 0) dl for (..., 3) unit normals (seed 000 eq. 4 without k_d/π)."""
    return _kernel_sum(image, normals, lambda c: np.maximum(c, 0.0))


def phong(
    image: npt.ArrayLike, reflections: npt.ArrayLike, exponent: float
) -> npt.NDArray[np.float64]:
    """Normalised Phong lobe of seed 000 eq. 7, L(r) = (N+1)/2π ∫ max(r·l, 0)^N L(l) dl.

    The normalisation (N + 1)/2π makes the lobe integrate to 1 over the
    hemisphere about r, so a constant environment L gives L.
    """
    scale = (exponent + 1.0) / (2.0 * np.pi)
    return _kernel_sum(image, reflections, lambda c: scale * np.maximum(c, 0.0) ** exponent)
