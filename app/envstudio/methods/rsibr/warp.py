"""Seed 002's sphere-map warps (§3.2, §3.3) and the camera frames they use.

Every radiance map of reflection-space IBR (the baked ones and the generated one)
is a sphere map in the local frame of the camera that made it (§3.3): x right,
y up, z from the origin toward the camera, with T the 3 × 3 matrix whose columns
are those axes in world space (world = T @ local). A texel p = (s, t) is the
point of a mirror ball seen along −z whose normal is n and whose mirror
reflection of the view is r (§2, Figure 1); with the sphere-map convention of
DESIGN.md (core.spheremap) the maps between them are, the extraction of §3.3
having garbled the matrices:

    g_normal(s, t)        = (2s − 1, 2t − 1, sqrt(1 − (2s − 1)² − (2t − 1)²))      (§3.3)
    g_normal⁻¹(x, y, z)   = (x/2 + ½, y/2 + ½)                                       (§3.3)
    g_mirror(s, t)        = (2xz, 2yz, 2z² − 1),  (x, y, z) = g_normal(s, t)         (§3.3)
    g_mirror⁻¹(x, y, z)   = g_normal⁻¹((x, y, z + 1) / sqrt(x² + y² + (z + 1)²))     (§3.3)

Derivation: the ball's unit normal under the orthographic view is its visible
point, n = (p, q, sqrt(1 − p² − q²)) with (p, q) = 2(s, t) − 1; the mirror
direction of the view vector e = (0, 0, 1) about n is r = 2(n·e)n − e =
(2 n_z n_x, 2 n_z n_y, 2 n_z² − 1); conversely n is the half vector of e and r,
(r + e)/|r + e|, whose x, y are 2(s, t) − 1. g_mirror⁻¹ is core.spheremap's
direction_to_uv (m = 2|r + e|), so the destination lookup is the hardware's
GL_SPHERE_MAP. The round trips are tested (tests/test_rsibr_math.py).

The warp from a source map to the destination map (§3.2) is

    p_d = g_d⁻¹ ∘ T_d⁻¹ ∘ T_s ∘ g_s(p_s),

with g = g_mirror for mirror-like BRDFs (Phong, the car paint) and g = g_normal
for diffuse ones (§3.3). §3.3 writes both chains ending in g_mirror⁻¹ "since we
have graphics hardware to do mirror reflections with a sphere map"; taken
literally, p_d = g_mirror⁻¹(T_d⁻¹ T_s g_normal(p_s)) is not the identity when
T_d = T_s (it sends the normal n to the texel whose *reflection* is n). What the
hardware gives is g_mirror⁻¹(r) = g_normal⁻¹(n): the texel of a mirror direction
and of its normal are the same, so the normal chain ends in g_normal⁻¹ =
g_mirror⁻¹ ∘ g_mirror ∘ g_normal⁻¹ and the generated map is looked up by
GL_SPHERE_MAP in both cases. Both warps are then the identity into their own
frame (tested).

Singularity (§3.3): the mirror warp fails where r is opposite the source view,
r = −v_s; in the destination map it lies at g_mirror⁻¹(T_d⁻¹(−v_s)), and the
source is faded by the distance from there (:func:`singularity_uv`). The normal
warp has no such point but the source holds only the normals with n · v_s > 0:
its confidence falls with that cosine, which is zero on the source's rim.

The disk (§3.3) is drawn in the destination map, so what the GPU evaluates per
vertex is the inverse warp p_s = g_s⁻¹ ∘ T_s⁻¹ ∘ T_d ∘ g_d(p_d)
(:func:`source_uv`), the texture coordinate of the source map at the vertex.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.core.latlong import _as_vectors

__all__ = [
    "WARPS",
    "g_inverse",
    "g_mirror",
    "g_mirror_inverse",
    "g_normal",
    "g_normal_inverse",
    "g_warp",
    "singularity_uv",
    "source_uv",
    "view_frame",
    "warp_uv",
]

#: Warp names: the central reflection direction the warp matches (§3.3).
WARPS = ("mirror", "normal")


def g_normal(uv: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """§3.3 g_normal: sphere-map point → unit surface normal, map-local frame.

    Parameters
    ----------
    uv : (..., 2) float
        (s, t); points outside the disc are pulled onto its rim.

    Returns
    -------
    (..., 3) float64
        (2s − 1, 2t − 1, sqrt(1 − (2s − 1)² − (2t − 1)²)).
    """
    pq = 2.0 * _as_vectors(uv, 2, "uv") - 1.0
    rho2 = np.sum(pq * pq, axis=-1, keepdims=True)
    pq = np.where(rho2 > 1.0, pq / np.sqrt(np.maximum(rho2, 1.0)), pq)
    nz = np.sqrt(np.maximum(1.0 - np.sum(pq * pq, axis=-1, keepdims=True), 0.0))
    return np.concatenate([pq, nz], axis=-1)


def g_normal_inverse(normals: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """§3.3 g_normal⁻¹(x, y, z) = (x/2 + ½, y/2 + ½) for unit normals (..., 3) → (..., 2)."""
    n = _as_vectors(normals, 3, "normals")
    return 0.5 * n[..., :2] + 0.5


def g_mirror(uv: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """§3.3 g_mirror: sphere-map point → unit mirror direction, map-local frame.

    Parameters
    ----------
    uv : (..., 2) float
        (s, t).

    Returns
    -------
    (..., 3) float64
        (2xz, 2yz, 2z² − 1) with (x, y, z) = g_normal(s, t).
    """
    n = g_normal(uv)
    z = n[..., 2:]
    return np.concatenate([2.0 * n[..., :2] * z, 2.0 * z * z - 1.0], axis=-1)


def g_mirror_inverse(directions: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """§3.3 g_mirror⁻¹(x, y, z) = g_normal⁻¹((x, y, z + 1) / |(x, y, z + 1)|).

    Parameters
    ----------
    directions : (..., 3) float
        Map-local directions, any non-zero length.

    Returns
    -------
    (..., 2) float64
        (s, t); exactly (0, 0, −1) goes to the rim point (½, 0) as in core.spheremap.
    """
    r = _as_vectors(directions, 3, "directions")
    r = r / np.linalg.norm(r, axis=-1, keepdims=True)
    h = r + np.array([0.0, 0.0, 1.0])
    length = np.linalg.norm(h, axis=-1, keepdims=True)
    singular = length[..., 0] == 0.0
    n = np.where(singular[..., None], [0.0, -1.0, 0.0], h / np.where(length == 0.0, 1.0, length))
    return g_normal_inverse(n)


def g_warp(uv: npt.ArrayLike, warp: str) -> npt.NDArray[np.float64]:
    """g of ``warp`` ("mirror" or "normal"): (..., 2) → (..., 3) map-local direction."""
    return g_mirror(uv) if _check(warp) == "mirror" else g_normal(uv)


def g_inverse(directions: npt.ArrayLike, warp: str) -> npt.NDArray[np.float64]:
    """g⁻¹ of ``warp`` ("mirror" or "normal"): (..., 3) → (..., 2)."""
    if _check(warp) == "mirror":
        return g_mirror_inverse(directions)
    n = _as_vectors(directions, 3, "directions")
    return g_normal_inverse(n / np.linalg.norm(n, axis=-1, keepdims=True))


def view_frame(view: npt.ArrayLike, up: npt.ArrayLike = (0.0, 1.0, 0.0)) -> np.ndarray:
    """T for a camera looking from ``view`` at the origin (§3.3).

    Parameters
    ----------
    view : (3,) float
        World-space direction from the origin toward the camera (any non-zero length).
    up : (3,) float
        World-space up; where it is (nearly) parallel to ``view``, −Z (looking down)
        or +Z (looking up) is used instead.

    Returns
    -------
    (3, 3) float64
        Columns x (right), y (up), z (toward the camera) in world space: world = T @ local.
    """
    z = np.asarray(view, dtype=np.float64)
    z = z / np.linalg.norm(z)
    up = np.asarray(up, dtype=np.float64)
    x = np.cross(up, z)
    if np.linalg.norm(x) < 1e-6:
        x = np.cross([0.0, 0.0, -np.sign(z[1]) or -1.0], z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z], axis=1)


def warp_uv(
    uv_s: npt.ArrayLike, frame_s: npt.ArrayLike, frame_d: npt.ArrayLike, warp: str
) -> npt.NDArray[np.float64]:
    """§3.2's forward warp p_d = g⁻¹ ∘ T_d⁻¹ ∘ T_s ∘ g(p_s).

    Parameters
    ----------
    uv_s : (..., 2) float
        Points of the source map.
    frame_s, frame_d : (3, 3) float
        Source and destination frames T (:func:`view_frame`).
    warp
        "mirror" or "normal".

    Returns
    -------
    (..., 2) float64
        Points of the destination map.
    """
    m = np.asarray(frame_d, dtype=np.float64).T @ np.asarray(frame_s, dtype=np.float64)
    return g_inverse(g_warp(uv_s, warp) @ m.T, warp)


def source_uv(
    uv_d: npt.ArrayLike, frame_s: npt.ArrayLike, frame_d: npt.ArrayLike, warp: str
) -> npt.NDArray[np.float64]:
    """The inverse warp p_s = g⁻¹ ∘ T_s⁻¹ ∘ T_d ∘ g(p_d): the disk's texture coordinates.

    Parameters are those of :func:`warp_uv` with the roles of the points swapped.
    """
    return warp_uv(uv_d, frame_d, frame_s, warp)


def singularity_uv(frame_s: npt.ArrayLike, frame_d: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """(2,) float64 where the source's mirror-warp singularity, −v_s, lands in the destination.

    §3.3: g_mirror⁻¹(T_d⁻¹ (−v_s)), v_s the source frame's z axis.
    """
    v_s = np.asarray(frame_s, dtype=np.float64)[:, 2]
    return g_mirror_inverse(np.asarray(frame_d, dtype=np.float64).T @ -v_s)


def _check(warp: str) -> str:
    if warp not in WARPS:
        raise ValueError(f"warp must be one of {WARPS}, got {warp!r}")
    return warp
