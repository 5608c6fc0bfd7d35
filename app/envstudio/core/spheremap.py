"""Sphere map (gazing ball, OpenGL ``GL_SPHERE_MAP``) parameterization.

Convention (DESIGN.md, "Conventions"; OpenGL 1.x texture-coordinate generation):
directions are in *view space* (the camera looks down −Z). For a unit
reflection direction r::

    m = 2 · sqrt(rx² + ry² + (rz + 1)²)        (s, t) = (rx / m + ½, ry / m + ½)

The image is a mirror ball photographed by that camera: the centre (½, ½) is
+Z (straight back at the viewer) and the rim s² + t² = ¼ around (½, ½) is −Z.
With (p, q) = (2s − 1, 2t − 1) and ρ² = p² + q² the ball's normal is
n = (p, q, sqrt(1 − ρ²)) and r = (2 n_z p, 2 n_z q, 2 n_z² − 1). The polar angle
θ of r from +Z satisfies sin(θ/2) = ρ, which makes the map equal-area (Lambert
azimuthal): dω = 4 dp dq = 16 ds dt inside the disc.

Singularity: r = (0, 0, −1) maps to the whole rim, so the map cannot be
inverted there and its texels near the rim cover strongly stretched, nearly
opposite neighbourhoods of −Z. :func:`direction_to_uv` sends r = (0, 0, −1)
to the rim point (½, 0); :func:`uv_to_direction` returns (0, 0, −1) for every
point on or outside the rim, so texels outside the disc hold the rim's value.

Images are (n, n, ...): ``img[i, j]`` at row i ↔ t and column j ↔ s, centred at
((j + ½)/n, (i + ½)/n); row 0 is t = 0, the bottom of the ball (−Y), the row
uploaded first. Turn it upside down (``img[::-1]``) to view it upright.
shaders/common/spheremap.glsl is the GLSL twin.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.core.latlong import _as_vectors

__all__ = [
    "direction_to_uv",
    "texel_directions",
    "texel_solid_angles",
    "uv_to_direction",
    "view_rotation_matrix",
]


def direction_to_uv(directions: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Sphere-map coordinates of view-space reflection directions.

    Parameters
    ----------
    directions
        (..., 3) float, view space; need not be unit length but must not be zero.

    Returns
    -------
    (..., 2) float64
        (s, t) = (rx/m + ½, ry/m + ½) with m = 2·sqrt(rx² + ry² + (rz + 1)²), inside the
        disc of radius ½ around (½, ½); exactly (0, 0, −1) gives the rim point (½, 0).
    """
    r = _as_vectors(directions, 3, "directions")
    r = r / np.linalg.norm(r, axis=-1, keepdims=True)
    m = 2.0 * np.sqrt(r[..., 0] ** 2 + r[..., 1] ** 2 + (r[..., 2] + 1.0) ** 2)
    singular = m == 0.0
    safe = np.where(singular, 1.0, m)[..., None]
    st = np.where(singular[..., None], [0.0, -0.5], r[..., :2] / safe)
    return st + 0.5


def uv_to_direction(uv: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """View-space unit directions of sphere-map coordinates (inverse of :func:`direction_to_uv`).

    Parameters
    ----------
    uv
        (..., 2) float, (s, t).

    Returns
    -------
    (..., 3) float64
        r = (2 n_z p, 2 n_z q, 2 n_z² − 1) with (p, q) = (2s − 1, 2t − 1) and
        n_z = sqrt(1 − p² − q²); (0, 0, −1) on and outside the rim.
    """
    c = _as_vectors(uv, 2, "uv")
    pq = 2.0 * c - 1.0
    nz = np.sqrt(np.maximum(1.0 - np.sum(pq * pq, axis=-1), 0.0))
    return np.concatenate([2.0 * nz[..., None] * pq, (2.0 * nz * nz - 1.0)[..., None]], axis=-1)


def texel_directions(size: int) -> npt.NDArray[np.float64]:
    """View-space directions of the texel centres of an n × n sphere map.

    Parameters
    ----------
    size
        Image edge n in texels.

    Returns
    -------
    (n, n, 3) float64
        Unit direction of ``img[i, j]`` at ((j + ½)/n, (i + ½)/n); (0, 0, −1) outside the disc.
    """
    if size < 1:
        raise ValueError(f"sphere map size must be positive, got {size}")
    st = (np.arange(size) + 0.5) / size
    ss, tt = np.meshgrid(st, st)
    return uv_to_direction(np.stack([ss, tt], axis=-1))


def texel_solid_angles(size: int) -> npt.NDArray[np.float64]:
    """Exact solid angle of every texel of an n × n sphere map.

    The map is equal-area, dω = 4 dp dq (module docstring), so a texel's solid angle is
    4 × the area of its square in (p, q) clipped to the unit disc. That area follows
    by inclusion–exclusion over the square's corners from the area of
    [0, a] × [0, b] ∩ disc (ab inside; else the two triangles under the lines and the
    circular sector between them). Texels outside the disc get 0; the total is 4π.
    The rim texels all share the neighbourhood of the singular direction (0, 0, −1).

    Parameters
    ----------
    size
        Image edge n in texels.

    Returns
    -------
    (n, n) float64
        Steradians.
    """
    if size < 1:
        raise ValueError(f"sphere map size must be positive, got {size}")
    edges = 2.0 * np.arange(size + 1) / size - 1.0
    a, b = np.meshgrid(edges, edges)
    area = np.sign(a) * np.sign(b) * _quadrant_area(np.abs(a), np.abs(b))
    return 4.0 * (area[:-1, :-1] - area[1:, :-1] - area[:-1, 1:] + area[1:, 1:])


def view_rotation_matrix(view_rotation: npt.ArrayLike | None = None) -> npt.NDArray[np.float64]:
    """Check a sphere-map camera's world-from-view rotation.

    Parameters
    ----------
    view_rotation
        (3, 3) float whose columns are the camera's x, y and z axes in world space
        (world = R @ view), or None.

    Returns
    -------
    (3, 3) float64
        The rotation; the identity for None.

    Raises
    ------
    ValueError
        If it is not a 3 × 3 orthonormal matrix.
    """
    if view_rotation is None:
        return np.eye(3)
    R = np.asarray(view_rotation, dtype=np.float64)
    if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-6):
        raise ValueError(f"view_rotation must be a 3x3 rotation matrix, got {R.tolist()}")
    return R


def _quadrant_area(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Area of [0, a] × [0, b] ∩ unit disc, for a, b ≥ 0."""
    ac, bc = np.minimum(a, 1.0), np.minimum(b, 1.0)
    clipped = 0.5 * (
        ac * np.sqrt(1.0 - ac * ac) + (np.arcsin(bc) - np.arccos(ac)) + bc * np.sqrt(1.0 - bc * bc)
    )
    return np.where(a * a + b * b <= 1.0, a * b, clipped)
