"""Order-2 real spherical harmonics (9 coefficients) for diffuse lighting.

Basis and order exactly as seed 000 (Kautz et al.), section 4.1, eq. 9, for a
unit direction l = (x, y, z) in world space::

    Y0         = 1 / sqrt(4π)
    Y1, Y2, Y3 = sqrt(3 / 4π)  · (y, z, x)
    Y4, Y5, Y7 = sqrt(15 / 4π) · (xy, yz, xz)
    Y6         = sqrt(5 / 16π) · (3z² − 1)
    Y8         = sqrt(15 / 16π) · (x² − y²)

These are orthonormal on the sphere. The coefficients of an environment are
L_i = ∫ L(l) Y_i(l) dl (eq. 11), evaluated here as Σ_texels L Y_i(centre) Δω with
the exact texel solid angles of each parameterization. Convolution with the
clamped cosine and lookup by the normal n combine into eq. 12::

    E(n) = Σ_i Â_i L_i Y_i(n),   Â = (π, 2π/3 ×3, π/4 ×5),

the irradiance, so the diffuse radiance is L_diffuse(n) = k_d / π · E(n).
shaders/common/sh.glsl is the GLSL twin.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.core import cubemap, latlong
from envstudio.core.latlong import _as_vectors

__all__ = [
    "A_HAT",
    "irradiance_sh9",
    "project_cube_sh9",
    "project_latlong_sh9",
    "project_sh9",
    "sh9_basis",
]

#: Â_i of seed 000 eq. 12: the clamped-cosine kernel's zonal coefficients times sqrt(4π/(2l+1)).
A_HAT = np.array([np.pi] + [2.0 * np.pi / 3.0] * 3 + [np.pi / 4.0] * 5)

_C0 = 1.0 / np.sqrt(4.0 * np.pi)
_C1 = np.sqrt(3.0 / (4.0 * np.pi))
_C2 = np.sqrt(15.0 / (4.0 * np.pi))
_C6 = np.sqrt(5.0 / (16.0 * np.pi))
_C8 = np.sqrt(15.0 / (16.0 * np.pi))


def sh9_basis(directions: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The 9 basis functions of seed 000 eq. 9 at the given directions.

    Parameters
    ----------
    directions
        (..., 3) float, unit length (not normalised here: the Y_i are polynomials).

    Returns
    -------
    (..., 9) float64
        Y_0 … Y_8 in the eq. 9 order.
    """
    d = _as_vectors(directions, 3, "directions")
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return np.stack(
        [
            np.full_like(x, _C0),
            _C1 * y,
            _C1 * z,
            _C1 * x,
            _C2 * x * y,
            _C2 * y * z,
            _C6 * (3.0 * z * z - 1.0),
            _C2 * x * z,
            _C8 * (x * x - y * y),
        ],
        axis=-1,
    )


def project_sh9(
    radiance: npt.ArrayLike, directions: npt.ArrayLike, solid_angles: npt.ArrayLike
) -> npt.NDArray[np.float64]:
    """SH coefficients by quadrature of eq. 11: L_i = Σ_k L(d_k) Y_i(d_k) Δω_k.

    Parameters
    ----------
    radiance
        (..., 3) float, linear RGB radiance of each sample.
    directions
        (..., 3) float, unit sample directions (texel centres).
    solid_angles
        (...) float, steradians per sample (exact texel solid angles).

    Returns
    -------
    (9, 3) float64
        L_i per colour channel.
    """
    L = _as_vectors(radiance, 3, "radiance")
    Y = sh9_basis(directions)
    w = np.asarray(solid_angles, dtype=np.float64)
    if not (L.shape[:-1] == Y.shape[:-1] == w.shape):
        raise ValueError(
            f"radiance {L.shape}, directions {Y.shape[:-1]} + (3,) and solid angles "
            f"{w.shape} must share their leading shape"
        )
    return np.einsum("ki,k,kc->ic", Y.reshape(-1, 9), w.reshape(-1), L.reshape(-1, 3))


def irradiance_sh9(coeffs: npt.ArrayLike, normals: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Irradiance E(n) = Σ Â_i L_i Y_i(n) (seed 000 eq. 12 without k_d / π).

    Parameters
    ----------
    coeffs
        (9, 3) float, L_i per colour channel from :func:`project_sh9`.
    normals
        (..., 3) float, unit surface normals, world space.

    Returns
    -------
    (..., 3) float64
        Irradiance (W m⁻² for radiance in W m⁻² sr⁻¹); a constant environment L gives πL.
        Multiply by k_d / π for the diffuse radiance L_diffuse.
    """
    c = np.asarray(coeffs, dtype=np.float64)
    if c.shape != (9, 3):
        raise ValueError(f"SH coefficients must have shape (9, 3), got {c.shape}")
    return sh9_basis(normals) @ (A_HAT[:, None] * c)


def project_cube_sh9(faces: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """SH coefficients of a cube map (core.cubemap layout).

    Parameters
    ----------
    faces
        (6, n, n, 3) float, linear radiance, OpenGL face order, rows ↔ t.

    Returns
    -------
    (9, 3) float64
    """
    faces = np.asarray(faces)
    if faces.ndim != 4 or faces.shape[0] != 6 or faces.shape[1] != faces.shape[2]:
        raise ValueError(f"cube faces must have shape (6, n, n, 3), got {faces.shape}")
    n = faces.shape[1]
    return project_sh9(faces, cubemap.texel_directions(n), cubemap.texel_solid_angles(n))


def project_latlong_sh9(image: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """SH coefficients of a lat-long map (core.latlong layout, row 0 = +Y).

    Parameters
    ----------
    image
        (h, w, 3) float, linear radiance.

    Returns
    -------
    (9, 3) float64
    """
    image = np.asarray(image)
    if image.ndim != 3:
        raise ValueError(f"lat-long image must have shape (h, w, 3), got {image.shape}")
    h, w = image.shape[:2]
    return project_sh9(image, latlong.texel_directions(h, w), latlong.texel_solid_angles(h, w))
