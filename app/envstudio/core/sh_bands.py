"""Real spherical harmonics of any band, in the convention of seed 000 eq. 9.

Seed 000 (section 4.1) lists the first 9 real basis functions; they are the
bands l = 0, 1, 2 of the real SH with z as the polar axis, m = −l … l in
order and no Condon–Shortley phase::

    Y_l^m(x, y, z) = K_l^m P̃_l^0(z)                       m = 0
                   = √2 K_l^m P̃_l^|m|(z) Re (x + iy)^m     m > 0
                   = √2 K_l^m P̃_l^|m|(z) Im (x + iy)^|m|   m < 0

    K_l^m = sqrt((2l + 1) / 4π · (l − |m|)! / (l + |m|)!)

where P̃_l^m is the associated Legendre function without its sinᵐθ factor
(that factor is carried by (x + iy)^m): P̃_m^m = (2m − 1)!!,
P̃_{m+1}^m = (2m + 1) z P̃_m^m, and
(l − m) P̃_l^m = (2l − 1) z P̃_{l−1}^m − (l + m − 1) P̃_{l−2}^m.
For l ≤ 2 this is exactly eq. 9 (core.sh.sh9_basis); shaders/common/sh_bands.glsl
runs the same recurrence.

Irradiance (Ramamoorthi and Hanrahan, seed 000 ref. 28, eq. 12 of the seed)
only needs the bands whose clamped-cosine coefficient Â_l is not zero:
l = 0, 1 and the even l ≥ 2. A *band set* is such a tuple of l; its
coefficient vector is the concatenation of m = −l … l per band, so the band set
(0, 1, 2) is eq. 9's order and (0, 1, 2, 4, 6) holds 31 of the 49 coefficients
of order 6 (bands 3 and 5 vanish under the cosine kernel).
"""

from __future__ import annotations

from math import factorial

import numpy as np
import numpy.typing as npt

from envstudio.core.latlong import _as_vectors

__all__ = [
    "BAND_SETS",
    "a_hat",
    "band_indices",
    "irradiance",
    "project",
    "sh_basis",
]

#: Band sets by the number of coefficients of the full order they stand for:
#: 9 (order 2, the seed's), 25 (order 4: 18 used) and 49 (order 6: 31 used).
BAND_SETS: dict[int, tuple[int, ...]] = {9: (0, 1, 2), 25: (0, 1, 2, 4), 49: (0, 1, 2, 4, 6)}


def a_hat(band: int) -> float:
    """Clamped-cosine coefficient Â_l of band l (seed 000 eq. 12, ref. 28).

    Â_0 = π, Â_1 = 2π/3, Â_l = 0 for odd l > 1 and, for even l,
    Â_l = 2π (−1)^(l/2 − 1) / ((l + 2)(l − 1)) · l! / (2^l ((l/2)!)²)
    (so Â_2 = π/4, Â_4 = −π/24, Â_6 = π/64).
    """
    if band < 0:
        raise ValueError(f"band must be non-negative, got {band}")
    if band == 0:
        return np.pi
    if band == 1:
        return 2.0 * np.pi / 3.0
    if band % 2:
        return 0.0
    half = band // 2
    return (
        2.0
        * np.pi
        * (-1.0) ** (half - 1)
        / ((band + 2) * (band - 1))
        * factorial(band)
        / (2.0**band * factorial(half) ** 2)
    )


def band_indices(bands: tuple[int, ...]) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Band l and order m of every coefficient of a band set, in storage order.

    Returns
    -------
    l, m
        (n,) int64 each, n = Σ (2l + 1).
    """
    degree = np.concatenate([np.full(2 * b + 1, b) for b in bands])
    order = np.concatenate([np.arange(-b, b + 1) for b in bands])
    return degree.astype(np.int64), order.astype(np.int64)


def _norm(band: int, m: int) -> float:
    return np.sqrt((2 * band + 1) / (4.0 * np.pi) * factorial(band - m) / factorial(band + m))


def sh_basis(directions: npt.ArrayLike, bands: tuple[int, ...]) -> npt.NDArray[np.float64]:
    """The real SH of a band set at the given directions (module docstring).

    Parameters
    ----------
    directions
        (..., 3) float, unit length (the Y are polynomials; nothing is normalised).
    bands
        Increasing band numbers, e.g. ``BAND_SETS[49]``.

    Returns
    -------
    (..., n) float64
        Y in storage order: per band, m = −l … l.
    """
    d = _as_vectors(directions, 3, "directions")
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    if list(bands) != sorted(set(bands)) or bands[0] < 0:
        raise ValueError(f"bands must be increasing and non-negative, got {bands}")
    top = bands[-1]
    offsets = {}
    count = 0
    for b in bands:
        offsets[b] = count
        count += 2 * b + 1
    out = np.empty((*d.shape[:-1], count))
    re, im = np.ones_like(x), np.zeros_like(x)  # (x + iy)^m
    pmm = np.ones_like(x)  # P̃_m^m = (2m − 1)!!
    for m in range(top + 1):
        if m:
            re, im = re * x - im * y, re * y + im * x
            pmm = pmm * (2 * m - 1)
        previous, current = np.zeros_like(x), pmm
        for band in range(m, top + 1):
            if band > m:
                previous, current = (
                    current,
                    ((2 * band - 1) * z * current - (band + m - 1) * previous) / (band - m),
                )
            if band not in offsets:
                continue
            centre = offsets[band] + band
            if m == 0:
                out[..., centre] = _norm(band, 0) * current
            else:
                k = np.sqrt(2.0) * _norm(band, m) * current
                out[..., centre + m] = k * re
                out[..., centre - m] = k * im
    return out


def project(
    radiance: npt.ArrayLike,
    directions: npt.ArrayLike,
    solid_angles: npt.ArrayLike,
    bands: tuple[int, ...],
) -> npt.NDArray[np.float64]:
    """Coefficients L_i = Σ_k L(d_k) Y_i(d_k) Δω_k (seed 000 eq. 11 by quadrature).

    Parameters
    ----------
    radiance
        (..., 3) float, linear RGB radiance per sample.
    directions
        (..., 3) float, unit sample directions.
    solid_angles
        (...) float, steradians per sample.
    bands
        Band set.

    Returns
    -------
    (n, 3) float64
        L_i per colour channel, storage order.
    """
    L = _as_vectors(radiance, 3, "radiance").reshape(-1, 3)
    Y = sh_basis(directions, bands).reshape(len(L), -1)
    w = np.asarray(solid_angles, dtype=np.float64).reshape(-1)
    if len(w) != len(L):
        raise ValueError(f"{len(L)} radiance samples but {len(w)} solid angles")
    return Y.T @ (L * w[:, None])


def irradiance(
    coefficients: npt.ArrayLike, normals: npt.ArrayLike, bands: tuple[int, ...]
) -> npt.NDArray[np.float64]:
    """E(n) = Σ_i Â_l(i) L_i Y_i(n) (seed 000 eq. 12 without k_d / π).

    Parameters
    ----------
    coefficients
        (n, 3) float, L_i of :func:`project`.
    normals
        (..., 3) float, unit normals.
    bands
        Band set of ``coefficients``.

    Returns
    -------
    (..., 3) float64
        Irradiance, radiance units × sr.
    """
    c = np.asarray(coefficients, dtype=np.float64)
    degree, _ = band_indices(bands)
    if c.shape != (len(degree), 3):
        raise ValueError(f"coefficients must have shape ({len(degree)}, 3), got {c.shape}")
    scale = np.array([a_hat(int(b)) for b in degree])
    return sh_basis(normals, bands) @ (scale[:, None] * c)
