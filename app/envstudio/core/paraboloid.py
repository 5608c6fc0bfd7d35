"""Dual-paraboloid parameterization (Heidrich and Seidel 1998).

Convention (DESIGN.md, "Conventions"): world space, right-handed, +Y up. For a
unit direction d = (x, y, z)::

    front face (0), z ≥ 0:   (s, t) = (x, y) / (1 + z)
    back face  (1), z < 0:   (s, t) = (x, y) / (1 − z)

(s, t) ∈ [−1, 1]² and the unit disc s² + t² ≤ 1 holds one hemisphere. Each
face is an n × n texture with a border of B texels: the disc spans the central
n − 2B texels, so the texture coordinate is::

    tex = 0.5 + 0.5 · s · (n − 2B) / n          (same for t)

The inverse (a stereographic projection) is
d = (2s, 2t, ±(1 − s² − t²)) / (1 + s² + t²), + on the front face. It is
defined beyond the disc too: a border texel holds the direction just past the
rim on the other hemisphere, so bilinear lookups at the rim stay continuous.
Its solid-angle element is dω = 4 / (1 + s² + t²)² ds dt.

Arrays are (2, n, n, ...): ``maps[f, i, j]`` is face f at row i ↔ t and column
j ↔ s, centred at tex = ((j + ½)/n, (i + ½)/n); row 0 is t = 0, the row uploaded
first. The front face is the picture a viewer on the +Z axis sees in a
paraboloid mirror (with t growing upwards); the back face uses the same (x, y)
axes and so is that picture mirrored left–right for a viewer on −Z.
shaders/common/paraboloid.glsl is the GLSL twin.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.core.latlong import _as_vectors

__all__ = [
    "direction_to_uv",
    "disc_scale",
    "texel_directions",
    "texel_solid_angles",
    "uv_to_direction",
]


def direction_to_uv(
    directions: npt.ArrayLike, size: int, border: float = 0
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
    """Paraboloid face and texture coordinates of directions.

    Parameters
    ----------
    directions
        (..., 3) float, world space; need not be unit length but must not be zero.
    size
        Face edge n in texels.
    border
        Border B in texels outside the unit disc, 0 ≤ B < n/2.

    Returns
    -------
    face
        (...) int64: 0 (front, z ≥ 0) or 1 (back, z < 0).
    uv
        (..., 2) float64 texture coordinates in [B/n, 1 − B/n]².
    """
    scale = disc_scale(size, border)
    d = _as_vectors(directions, 3, "directions")
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    face = np.where(d[..., 2] >= 0.0, 0, 1).astype(np.int64)
    # Heidrich–Seidel: (s, t) = (x, y) / (1 + |z|) on the face of z's sign.
    st = d[..., :2] / (1.0 + np.abs(d[..., 2:3]))
    return face, 0.5 + 0.5 * st * scale


def uv_to_direction(
    face: npt.ArrayLike, uv: npt.ArrayLike, size: int, border: float = 0
) -> npt.NDArray[np.float64]:
    """Unit directions of paraboloid texture coordinates (inverse of :func:`direction_to_uv`).

    Parameters
    ----------
    face
        (...) int, 0 (front) or 1 (back), broadcast against ``uv[..., 0]``.
    uv
        (..., 2) float texture coordinates; points outside the disc (the border)
        continue onto the other hemisphere.
    size, border
        Face edge n and border B in texels.

    Returns
    -------
    (..., 3) float64
        Unit directions, world space: (2s, 2t, ±(1 − s² − t²)) / (1 + s² + t²).
    """
    scale = disc_scale(size, border)
    c = _as_vectors(uv, 2, "uv")
    face = np.asarray(face)
    if np.any((face != 0) & (face != 1)):
        raise ValueError("paraboloid face indices must be 0 (front, z >= 0) or 1 (back)")
    st = (2.0 * c - 1.0) / scale
    r2 = np.sum(st * st, axis=-1)
    z = np.where(face == 0, 1.0, -1.0) * (1.0 - r2)
    return np.concatenate([2.0 * st, z[..., None]], axis=-1) / (1.0 + r2)[..., None]


def texel_directions(size: int, border: float = 0) -> npt.NDArray[np.float64]:
    """Directions of the texel centres of both faces.

    Parameters
    ----------
    size, border
        Face edge n and border B in texels.

    Returns
    -------
    (2, n, n, 3) float64
        Unit direction of ``maps[f, i, j]`` at tex = ((j + ½)/n, (i + ½)/n).
    """
    st = (np.arange(size) + 0.5) / size
    ss, tt = np.meshgrid(st, st)
    uv = np.broadcast_to(np.stack([ss, tt], axis=-1), (2, size, size, 2))
    return uv_to_direction(np.arange(2)[:, None, None], uv, size, border)


def texel_solid_angles(size: int, border: float = 0) -> npt.NDArray[np.float64]:
    """Exact solid angle of every texel of both faces, counting only the unit disc.

    The solid angle of a texel rectangle R in (s, t) is ∫∫_{R ∩ disc} 4 / (1 + r²)² ds dt,
    evaluated in closed form: by inclusion–exclusion over R's corners it reduces to
    H(a, b) = the integral over [0, a] × [0, b] ∩ disc (odd in a and in b). In polar
    coordinates the integrand integrates radially to G(r) = 2r² / (1 + r²), and along a
    line at distance p, ∫₀^Θ G(p / cos θ) dθ = 2p / sqrt(1 + p²) · atan(p tan Θ / sqrt(1 + p²)).
    Texels outside the disc get 0, texels on the rim their exact share; each face sums to 2π.

    Parameters
    ----------
    size, border
        Face edge n and border B in texels.

    Returns
    -------
    (2, n, n) float64
        Steradians, indexed like the face arrays.
    """
    edges = (2.0 * np.arange(size + 1) / size - 1.0) / disc_scale(size, border)
    a, b = np.meshgrid(edges, edges)
    H = np.sign(a) * np.sign(b) * _quadrant_integral(np.abs(a), np.abs(b))
    face = H[:-1, :-1] - H[1:, :-1] - H[:-1, 1:] + H[1:, 1:]
    return np.broadcast_to(face, (2, size, size)).copy()


def _quadrant_integral(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """∫∫ over [0, a] × [0, b] ∩ unit disc of 4 / (1 + s² + t²)² ds dt, for a, b ≥ 0."""
    ka, kb = np.sqrt(1.0 + a * a), np.sqrt(1.0 + b * b)
    # Corner inside the disc: the lines s = a (θ < atan(b/a)) and t = b bound the region.
    inside = 2.0 * a / ka * np.arctan(b / ka) + 2.0 * b / kb * np.arctan(a / kb)
    # Corner outside: line s = a up to θ = acos a, the rim (G = 1) to θ = asin b, line t = b.
    ac, bc = np.minimum(a, 1.0), np.minimum(b, 1.0)
    kac, kbc = np.sqrt(1.0 + ac * ac), np.sqrt(1.0 + bc * bc)
    line_a = 2.0 * ac / kac * np.arctan(np.sqrt(1.0 - ac * ac) / kac)
    line_b = 2.0 * bc / kbc * np.arctan(np.sqrt(1.0 - bc * bc) / kbc)
    clipped = line_a + (np.arcsin(bc) - np.arccos(ac)) + line_b
    return np.where(a * a + b * b <= 1.0, inside, clipped)


def disc_scale(size: int, border: float) -> float:
    """The fraction (n − 2B) / n of a face's width that the unit disc spans.

    Parameters
    ----------
    size, border
        Face edge n and border B in texels.

    Returns
    -------
    float
        (n − 2B) / n.

    Raises
    ------
    ValueError
        Unless n ≥ 1 and 0 ≤ B < n/2.
    """
    if size < 1 or not 0 <= border < size / 2:
        raise ValueError(
            f"paraboloid face needs size >= 1 and 0 <= border < size/2, got {size}, {border}"
        )
    return (size - 2.0 * border) / size
