"""Latitude–longitude (equirectangular) parameterization of the sphere.

Convention (DESIGN.md, "Conventions"): world space is right-handed with +Y up.
For a direction d = (x, y, z)::

    u = 0.5 + atan2(x, -z) / 2π        v = acos(y) / π

so v = 0 is +Y (the zenith), v = 1 is −Y, and the image centre (u, v) = (½, ½)
looks down −Z. Along a row::

    u :   0      ¼      ½      ¾      1
          +Z     −X     −Z     +X     +Z   (the seam u = 0 ≡ 1 faces +Z)

An (h, w) image (normally w = 2h) has its texel at row i, column j centred at
(u, v) = ((j + ½) / w, (i + ½) / h). Row 0 is +Y, which is also row 0 of an
image file (io.images), and when the array is uploaded row 0 first the texture
coordinate is (s, t) = (u, v); shaders/common/latlong.glsl is the GLSL twin.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = ["direction_to_uv", "texel_directions", "texel_solid_angles", "uv_to_direction"]


def direction_to_uv(directions: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Lat-long coordinates of directions.

    Parameters
    ----------
    directions
        (..., 3) float, world space; need not be unit length but must not be zero.

    Returns
    -------
    (..., 2) float64
        (u, v) in [0, 1]²: u = 0.5 + atan2(x, −z)/2π, v = acos(y/|d|)/π (DESIGN.md).
    """
    d = _as_vectors(directions, 3, "directions")
    length = np.linalg.norm(d, axis=-1)
    u = 0.5 + np.arctan2(d[..., 0], -d[..., 2]) / (2.0 * np.pi)
    v = np.arccos(np.clip(d[..., 1] / length, -1.0, 1.0)) / np.pi
    return np.stack([u, v], axis=-1)


def uv_to_direction(uv: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Unit directions of lat-long coordinates (inverse of :func:`direction_to_uv`).

    With φ = 2π(u − ½) and θ = πv: d = (sin θ sin φ, cos θ, −sin θ cos φ).

    Parameters
    ----------
    uv
        (..., 2) float, (u, v); u is periodic with period 1.

    Returns
    -------
    (..., 3) float64
        Unit directions, world space.
    """
    c = _as_vectors(uv, 2, "uv")
    phi = 2.0 * np.pi * (c[..., 0] - 0.5)
    theta = np.pi * c[..., 1]
    sin_theta = np.sin(theta)
    return np.stack(
        [sin_theta * np.sin(phi), np.cos(theta), -sin_theta * np.cos(phi)],
        axis=-1,
    )


def texel_directions(height: int, width: int | None = None) -> npt.NDArray[np.float64]:
    """Directions of the texel centres of an (height, width) lat-long image.

    Parameters
    ----------
    height, width
        Image size in texels; ``width`` defaults to ``2 * height``.

    Returns
    -------
    (height, width, 3) float64
        Unit direction of texel (i, j) at (u, v) = ((j + ½)/w, (i + ½)/h); row 0 is near +Y.
    """
    height, width = _size(height, width)
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    uu, vv = np.meshgrid(u, v)
    return uv_to_direction(np.stack([uu, vv], axis=-1))


def texel_solid_angles(height: int, width: int | None = None) -> npt.NDArray[np.float64]:
    """Exact solid angle of every texel of an (height, width) lat-long image.

    The texel of row i spans θ ∈ [πi/h, π(i+1)/h] and Δφ = 2π/w, so its solid angle is
    the band integral ∫∫ sin θ dθ dφ = (2π/w)(cos(πi/h) − cos(π(i+1)/h)); the total is 4π.

    Parameters
    ----------
    height, width
        Image size in texels; ``width`` defaults to ``2 * height``.

    Returns
    -------
    (height, width) float64
        Steradians.
    """
    height, width = _size(height, width)
    edges = np.cos(np.pi * np.arange(height + 1) / height)
    band = (2.0 * np.pi / width) * (edges[:-1] - edges[1:])
    return np.repeat(band[:, None], width, axis=1)


def _size(height: int, width: int | None) -> tuple[int, int]:
    width = 2 * height if width is None else width
    if height < 1 or width < 1:
        raise ValueError(f"lat-long size must be positive, got {height}x{width} (h x w)")
    return int(height), int(width)


def _as_vectors(values: npt.ArrayLike, n: int, name: str) -> npt.NDArray[np.float64]:
    array = np.asarray(values, dtype=np.float64)
    if array.ndim == 0 or array.shape[-1] != n:
        raise ValueError(f"{name} must have shape (..., {n}), got {array.shape}")
    return array
