"""Bilinear lookups and resampling between sphere parameterizations, in NumPy.

This is the independent CPU reference for the GPU conversions of
envstudio.envmap.conversions, so it follows the same sampling rules as the GL
sampler state those use:

- lat-long: bilinear, wrapping in u (``REPEAT``) and clamped in v (``CLAMP_TO_EDGE``);
- cube: bilinear and seamless across faces, as ``GL_TEXTURE_CUBE_MAP_SEAMLESS``
  (which moderngl enables) filters: a footprint that leaves a face takes the
  adjacent face's edge texels; at the eight cube corners the missing fourth
  texel is the mean of the three that meet there (the rule ARB_seamless_cube_map
  recommends; drivers may differ within half a texel of a corner);
- dual paraboloid and sphere map: bilinear, clamped to the edge of each face.

Every conversion takes one such sample at each target texel centre, except
:func:`latlong_to_cube`, which averages k × k samples per texel when the
lat-long map is much finer than the cube (:func:`latlong_supersampling`).
Layouts and conventions are those of core.latlong, core.cubemap,
core.paraboloid and core.spheremap. Images are float32 linear radiance.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from envstudio.core import cubemap, latlong, paraboloid, spheremap

__all__ = [
    "cube_to_latlong",
    "cube_to_paraboloid",
    "cube_to_spheremap",
    "latlong_supersampling",
    "latlong_to_cube",
    "paraboloid_to_cube",
    "sample_cube",
    "sample_latlong",
    "sample_paraboloid",
    "sample_spheremap",
    "spheremap_to_cube",
]


def latlong_supersampling(height: int, size: int) -> int:
    """Samples k per cube-texel edge used by :func:`latlong_to_cube` (and the GPU twin).

    A cube texel at a face centre spans about 2/n radians, a lat-long texel π/h, so
    k = max(1, round(2h / (π n))) keeps one sample per lat-long texel or more.

    Parameters
    ----------
    height
        Lat-long height h in texels.
    size
        Cube face edge n in texels.

    Returns
    -------
    int
        k ≥ 1; the cube texel is the mean of k × k bilinear samples.
    """
    return max(1, round(2.0 * height / (math.pi * size)))


def sample_latlong(image: npt.ArrayLike, directions: npt.ArrayLike) -> npt.NDArray[np.float32]:
    """Bilinear lookup in a lat-long map.

    Parameters
    ----------
    image
        (h, w, c) float, row 0 = +Y (core.latlong).
    directions
        (..., 3) float, world space, non-zero.

    Returns
    -------
    (..., c) float32
        Values, wrapping in u and clamped in v.
    """
    image = _image(image, "lat-long image")
    h, w = image.shape[:2]
    uv = latlong.direction_to_uv(directions)
    return _bilinear(image, uv[..., 0] * w - 0.5, uv[..., 1] * h - 0.5, wrap_x=True)


def sample_cube(faces: npt.ArrayLike, directions: npt.ArrayLike) -> npt.NDArray[np.float32]:
    """Seamless bilinear lookup in a cube map (module docstring).

    Parameters
    ----------
    faces
        (6, n, n, c) float, core.cubemap layout.
    directions
        (..., 3) float, world space, non-zero.

    Returns
    -------
    (..., c) float32
    """
    faces = _faces(faces)
    padded = _pad_cube(faces)
    n = faces.shape[1]
    face, uv = cubemap.direction_to_uv(directions)
    # Texel coordinates in the padded face, whose texel 0 is the border.
    x = np.clip(uv[..., 0] * n + 0.5, 0.0, n + 1.0)
    y = np.clip(uv[..., 1] * n + 0.5, 0.0, n + 1.0)
    x0 = np.minimum(np.floor(x).astype(np.int64), n)
    y0 = np.minimum(np.floor(y).astype(np.int64), n)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    top = padded[face, y0, x0] * (1.0 - fx) + padded[face, y0, x0 + 1] * fx
    bottom = padded[face, y0 + 1, x0] * (1.0 - fx) + padded[face, y0 + 1, x0 + 1] * fx
    return (top * (1.0 - fy) + bottom * fy).astype(np.float32)


def sample_paraboloid(
    maps: npt.ArrayLike, directions: npt.ArrayLike, border: float = 0
) -> npt.NDArray[np.float32]:
    """Bilinear lookup in a dual-paraboloid map, clamped at each face's edge.

    Parameters
    ----------
    maps
        (2, n, n, c) float, core.paraboloid layout (front, back).
    directions
        (..., 3) float, world space, non-zero.
    border
        Border B in texels the maps were made with.

    Returns
    -------
    (..., c) float32
    """
    maps = np.asarray(maps, dtype=np.float64)
    if maps.ndim != 4 or maps.shape[0] != 2 or maps.shape[1] != maps.shape[2]:
        raise ValueError(f"paraboloid maps must have shape (2, n, n, c), got {maps.shape}")
    n = maps.shape[1]
    face, uv = paraboloid.direction_to_uv(directions, n, border)
    out = np.empty((*face.shape, maps.shape[3]), dtype=np.float32)
    for f in range(2):
        sel = face == f
        out[sel] = _bilinear(maps[f], uv[sel][:, 0] * n - 0.5, uv[sel][:, 1] * n - 0.5)
    return out


def sample_spheremap(image: npt.ArrayLike, directions: npt.ArrayLike) -> npt.NDArray[np.float32]:
    """Bilinear lookup in a sphere map, clamped at the image edge.

    Parameters
    ----------
    image
        (n, n, c) float, core.spheremap layout (row 0 = t = 0).
    directions
        (..., 3) float, *view space*, non-zero.

    Returns
    -------
    (..., c) float32
    """
    image = _image(image, "sphere map")
    h, w = image.shape[:2]
    uv = spheremap.direction_to_uv(directions)
    return _bilinear(image, uv[..., 0] * w - 0.5, uv[..., 1] * h - 0.5)


def latlong_to_cube(
    image: npt.ArrayLike, size: int, samples: int | None = None
) -> npt.NDArray[np.float32]:
    """Resample a lat-long map into a cube map.

    Parameters
    ----------
    image
        (h, w, c) float, row 0 = +Y.
    size
        Face edge n in texels.
    samples
        k: each cube texel averages k × k bilinear samples at the centres of a
        k × k grid of sub-texels; default :func:`latlong_supersampling`.

    Returns
    -------
    (6, n, n, c) float32
        core.cubemap layout.
    """
    image = _image(image, "lat-long image")
    k = latlong_supersampling(image.shape[0], size) if samples is None else int(samples)
    if k < 1:
        raise ValueError(f"samples must be at least 1, got {samples}")
    fine = sample_latlong(image, cubemap.texel_directions(size * k))
    return (
        fine.reshape(6, size, k, size, k, -1).mean(axis=(2, 4), dtype=np.float64).astype(np.float32)
    )


def cube_to_latlong(faces: npt.ArrayLike, height: int) -> npt.NDArray[np.float32]:
    """Resample a cube map into a lat-long map of the given height.

    Parameters
    ----------
    faces
        (6, n, n, c) float, core.cubemap layout.
    height
        h in texels; the width is 2h.

    Returns
    -------
    (h, 2h, c) float32
        Row 0 = +Y.
    """
    return sample_cube(faces, latlong.texel_directions(height))


def cube_to_paraboloid(
    faces: npt.ArrayLike, size: int, border: float = 0
) -> npt.NDArray[np.float32]:
    """Resample a cube map into a dual-paraboloid map; border texels get their
    (beyond-the-rim) directions' values.

    Parameters
    ----------
    faces
        (6, n, n, c) float, core.cubemap layout.
    size, border
        Paraboloid face edge and border B in texels.

    Returns
    -------
    (2, size, size, c) float32
        core.paraboloid layout.
    """
    return sample_cube(faces, paraboloid.texel_directions(size, border))


def paraboloid_to_cube(
    maps: npt.ArrayLike, size: int, border: float = 0
) -> npt.NDArray[np.float32]:
    """Resample a dual-paraboloid map into a cube map.

    Parameters
    ----------
    maps
        (2, m, m, c) float, core.paraboloid layout.
    size
        Cube face edge n in texels.
    border
        Border B in texels the maps were made with.

    Returns
    -------
    (6, n, n, c) float32
    """
    return sample_paraboloid(maps, cubemap.texel_directions(size), border)


def cube_to_spheremap(
    faces: npt.ArrayLike, size: int, view_rotation: npt.ArrayLike | None = None
) -> npt.NDArray[np.float32]:
    """Resample a cube map into the sphere map seen by a camera.

    Parameters
    ----------
    faces
        (6, n, n, c) float, core.cubemap layout.
    size
        Sphere map edge in texels.
    view_rotation
        (3, 3) float world-from-view rotation of the camera (columns: the camera's
        x, y, z axes in world space); default identity.

    Returns
    -------
    (size, size, c) float32
        core.spheremap layout; texels outside the disc hold the −Z (view) value.
    """
    R = spheremap.view_rotation_matrix(view_rotation)
    return sample_cube(faces, spheremap.texel_directions(size) @ R.T)


def spheremap_to_cube(
    image: npt.ArrayLike, size: int, view_rotation: npt.ArrayLike | None = None
) -> npt.NDArray[np.float32]:
    """Resample a sphere map taken with a camera into a (world-space) cube map.

    Parameters
    ----------
    image
        (m, m, c) float, core.spheremap layout.
    size
        Cube face edge n in texels.
    view_rotation
        (3, 3) float world-from-view rotation of the camera; default identity.

    Returns
    -------
    (6, n, n, c) float32
        Directions near view −Z come from the stretched rim (core.spheremap).
    """
    R = spheremap.view_rotation_matrix(view_rotation)
    return sample_spheremap(image, cubemap.texel_directions(size) @ R)


def _bilinear(
    image: np.ndarray, x: np.ndarray, y: np.ndarray, wrap_x: bool = False
) -> npt.NDArray[np.float32]:
    """Bilinear filter of (h, w, c) at texel coordinates (x, y) (texel centres at integers)."""
    h, w = image.shape[:2]
    x0f, y0f = np.floor(x), np.floor(y)
    fx, fy = (x - x0f)[..., None], (y - y0f)[..., None]
    x0, y0 = x0f.astype(np.int64), y0f.astype(np.int64)
    if wrap_x:
        xa, xb = x0 % w, (x0 + 1) % w
    else:
        xa, xb = np.clip(x0, 0, w - 1), np.clip(x0 + 1, 0, w - 1)
    ya, yb = np.clip(y0, 0, h - 1), np.clip(y0 + 1, 0, h - 1)
    top = image[ya, xa] * (1.0 - fx) + image[ya, xb] * fx
    bottom = image[yb, xa] * (1.0 - fx) + image[yb, xb] * fx
    return (top * (1.0 - fy) + bottom * fy).astype(np.float32)


def _pad_cube(faces: np.ndarray) -> np.ndarray:
    """Faces with a one-texel border taken from the adjacent faces (seamless filtering).

    Border texel centres lie half a texel outside the face. An edge texel takes the
    adjacent face's texel across that edge, found by stepping just over the edge on the
    face plane and projecting onto the cube; a corner texel is the mean of the face's
    corner texel and the two adjacent faces' texels across its two edges.
    """
    n = faces.shape[1]
    padded = np.zeros((6, n + 2, n + 2, faces.shape[3]), dtype=np.float64)
    padded[:, 1:-1, 1:-1] = faces
    ring = [
        (i, j) for i in range(n + 2) for j in range(n + 2) if i in (0, n + 1) or j in (0, n + 1)
    ]
    pi, pj = np.array(ring).T
    s, t = (pj - 0.5) / n, (pi - 0.5) / n
    eps = 1e-6
    s_in, t_in = np.clip(s, 0.5 / n, 1.0 - 0.5 / n), np.clip(t, 0.5 / n, 1.0 - 0.5 / n)
    s_out, t_out = np.where(s < 0, -eps, 1.0 + eps), np.where(t < 0, -eps, 1.0 + eps)
    outside_s, outside_t = (s < 0) | (s > 1), (t < 0) | (t > 1)
    corner = outside_s & outside_t
    # Points whose nearest texels are averaged: across the s edge, across the t edge,
    # and (corners only) the face's own corner texel.
    across_s = np.stack([np.where(outside_s, s_out, s_in), t_in], axis=-1)
    across_t = np.stack([s_in, np.where(outside_t, t_out, t_in)], axis=-1)
    own = np.stack([s_in, t_in], axis=-1)
    for face in range(6):
        values_s = _nearest_texel(faces, face, across_s)
        values_t = _nearest_texel(faces, face, across_t)
        values_own = _nearest_texel(faces, face, own)
        edge_value = np.where(outside_s[:, None], values_s, values_t)
        corner_value = (values_s + values_t + values_own) / 3.0
        padded[face, pi, pj] = np.where(corner[:, None], corner_value, edge_value)
    return padded


def _nearest_texel(faces: np.ndarray, face: int, st: np.ndarray) -> np.ndarray:
    """Texel nearest to the point ``st`` on (or just beyond) ``face``, after projection."""
    n = faces.shape[1]
    target, uv = cubemap.direction_to_uv(cubemap.uv_to_direction(face, st))
    j = np.clip(np.floor(uv[:, 0] * n).astype(np.int64), 0, n - 1)
    i = np.clip(np.floor(uv[:, 1] * n).astype(np.int64), 0, n - 1)
    return faces[target, i, j]


def _faces(faces: npt.ArrayLike) -> np.ndarray:
    faces = np.asarray(faces, dtype=np.float64)
    if faces.ndim != 4 or faces.shape[0] != 6 or faces.shape[1] != faces.shape[2]:
        raise ValueError(f"cube faces must have shape (6, n, n, c), got {faces.shape}")
    return faces


def _image(image: npt.ArrayLike, name: str) -> np.ndarray:
    image = np.asarray(image, dtype=np.float64)
    if image.ndim != 3:
        raise ValueError(f"{name} must have shape (h, w, c), got {image.shape}")
    return image
