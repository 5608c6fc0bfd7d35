"""Cube map parameterization in the OpenGL convention.

Faces are in OpenGL order (DESIGN.md, "Conventions")::

    0: +X   1: −X   2: +Y   3: −Y   4: +Z   5: −Z

A direction d picks the face of its major axis and (sc, tc, ma) from the
OpenGL specification's table (4.6 core, table 8.19 "Selection of cube map
images")::

    major axis   face   sc    tc    ma
    +x           +X     −z    −y    x
    −x           −X     +z    −y    x
    +y           +Y     +x    +z    y
    −y           −Y     +x    −z    y
    +z           +Z     +x    −y    z
    −z           −Z     −x    −y    z

    s = (sc / |ma| + 1) / 2        t = (tc / |ma| + 1) / 2

Ties between axes go to x, then y (|x| ≥ |y|, |z| → X; else |y| ≥ |z| → Y).

Face arrays are (6, n, n, ...): ``faces[f, i, j]`` is the texel of face f at
row i ↔ t and column j ↔ s, centred at (s, t) = ((j + ½)/n, (i + ½)/n). Row 0
is t = 0, the row ``glTexImage2D`` uploads first, so a face array is written
to a cube map texture as is. Drawn with row 0 at the top, the faces join into
the horizontal cross of :func:`faces_to_cross` (as Filament's Cubemap.h draws
it); each arrow is the direction in which s (→) or t (↓) grows, the corner
label the axis that direction points to::

                 +----------+
                 | +---->+x |
                 | |        |
                 | |  +Y  2 |
                 | +z       |
      +----------+----------+----------+----------+
      | +---->+z | +---->+x | +---->-z | +---->-x |
      | |        | |        | |        | |        |
      | |  −X  1 | |  +Z  4 | |  +X  0 | |  −Z  5 |
      | -y       | -y       | -y       | -y       |
      +----------+----------+----------+----------+
                 | +---->+x |
                 | |        |
                 | |  −Y  3 |
                 | -z       |
                 +----------+

The cross is continuous across every shared edge and shows the environment as
seen from outside the cube (mirrored left–right compared with a view from the
centre). shaders/common/cubemap.glsl is the GLSL twin.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.core.latlong import _as_vectors

__all__ = [
    "FACE_NAMES",
    "cross_to_faces",
    "direction_to_face_uv",
    "direction_to_uv",
    "face_uv_to_direction",
    "faces_to_cross",
    "texel_directions",
    "texel_solid_angles",
    "uv_to_direction",
]

FACE_NAMES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")

# Per face, the matrix M with d ∝ M (a, b, 1) where (a, b) = (sc, tc) / |ma| = (2s − 1, 2t − 1):
# the spec table solved for d.
_FACE_FROM_AB = np.array(
    [
        [[0, 0, 1], [0, -1, 0], [-1, 0, 0]],  # +X: d = (1, −b, −a)
        [[0, 0, -1], [0, -1, 0], [1, 0, 0]],  # −X: d = (−1, −b, a)
        [[1, 0, 0], [0, 0, 1], [0, 1, 0]],  # +Y: d = (a, 1, b)
        [[1, 0, 0], [0, 0, -1], [0, -1, 0]],  # −Y: d = (a, −1, −b)
        [[1, 0, 0], [0, -1, 0], [0, 0, 1]],  # +Z: d = (a, −b, 1)
        [[-1, 0, 0], [0, -1, 0], [0, 0, -1]],  # −Z: d = (−a, −b, −1)
    ],
    dtype=np.float64,
)

# Cross layout: face -> (block row, block column) in a 3 x 4 grid of n x n blocks.
_CROSS_BLOCKS = {2: (0, 1), 1: (1, 0), 4: (1, 1), 0: (1, 2), 5: (1, 3), 3: (2, 1)}


def direction_to_uv(
    directions: npt.ArrayLike,
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
    """Cube face and face coordinates of directions (OpenGL major-axis table).

    Parameters
    ----------
    directions
        (..., 3) float, world space; need not be unit length but must not be zero.

    Returns
    -------
    face
        (...) int64 in 0..5, OpenGL face order.
    uv
        (..., 2) float64, (s, t) in [0, 1]² on that face.
    """
    d = _as_vectors(directions, 3, "directions")
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    ax, ay, az = np.abs(x), np.abs(y), np.abs(z)
    use_x = (ax >= ay) & (ax >= az)
    use_y = ~use_x & (ay >= az)
    face = np.where(
        use_x,
        np.where(x >= 0, 0, 1),
        np.where(use_y, np.where(y >= 0, 2, 3), np.where(z >= 0, 4, 5)),
    )
    # (sc, tc, ma) per face, from the table in the module docstring.
    sc = np.choose(face, [-z, z, x, x, x, -x])
    tc = np.choose(face, [-y, -y, z, -z, -y, -y])
    ma = np.choose(face, [ax, ax, ay, ay, az, az])
    uv = np.stack([(sc / ma + 1.0) * 0.5, (tc / ma + 1.0) * 0.5], axis=-1)
    return face.astype(np.int64), uv


def uv_to_direction(face: npt.ArrayLike, uv: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Unit directions of face coordinates (inverse of :func:`direction_to_uv`).

    With a = 2s − 1 and b = 2t − 1 the table solves to
    +X: (1, −b, −a), −X: (−1, −b, a), +Y: (a, 1, b), −Y: (a, −1, −b),
    +Z: (a, −b, 1), −Z: (−a, −b, −1), then normalised. (s, t) outside [0, 1]
    extend the face plane.

    Parameters
    ----------
    face
        (...) int in 0..5, broadcast against ``uv[..., 0]``.
    uv
        (..., 2) float, (s, t).

    Returns
    -------
    (..., 3) float64
        Unit directions, world space.
    """
    c = _as_vectors(uv, 2, "uv")
    face = np.asarray(face)
    if np.any((face < 0) | (face > 5)):
        raise ValueError("cube face indices must be in 0..5 (+X, -X, +Y, -Y, +Z, -Z)")
    abc = np.stack([2.0 * c[..., 0] - 1.0, 2.0 * c[..., 1] - 1.0, np.ones(c.shape[:-1])], -1)
    d = np.einsum("...ij,...j->...i", _FACE_FROM_AB[face], abc)
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


direction_to_face_uv = direction_to_uv
face_uv_to_direction = uv_to_direction


def texel_directions(size: int) -> npt.NDArray[np.float64]:
    """Directions of the texel centres of an n × n cube map.

    Parameters
    ----------
    size
        Face edge n in texels.

    Returns
    -------
    (6, n, n, 3) float64
        Unit direction of ``faces[f, i, j]`` at (s, t) = ((j + ½)/n, (i + ½)/n).
    """
    st = _centres(size)
    ss, tt = np.meshgrid(st, st)
    uv = np.broadcast_to(np.stack([ss, tt], axis=-1), (6, size, size, 2))
    return uv_to_direction(np.arange(6)[:, None, None], uv)


def texel_solid_angles(size: int) -> npt.NDArray[np.float64]:
    """Exact solid angle of every texel of an n × n cube map.

    On the face plane at distance 1 with coordinates (a, b) ∈ [−1, 1]² the solid
    angle element is da db / (1 + a² + b²)^{3/2}, whose antiderivative is
    F(a, b) = atan2(ab, sqrt(a² + b² + 1)). A texel [a0, a1] × [b0, b1] subtends
    F(a0, b0) − F(a0, b1) − F(a1, b0) + F(a1, b1); all faces are alike and the total is 4π.

    Parameters
    ----------
    size
        Face edge n in texels.

    Returns
    -------
    (6, n, n) float64
        Steradians, indexed like the face arrays.
    """
    if size < 1:
        raise ValueError(f"cube face size must be positive, got {size}")
    edges = np.linspace(-1.0, 1.0, size + 1)
    a, b = np.meshgrid(edges, edges)
    F = np.arctan2(a * b, np.sqrt(a * a + b * b + 1.0))
    face = F[:-1, :-1] - F[1:, :-1] - F[:-1, 1:] + F[1:, 1:]
    return np.broadcast_to(face, (6, size, size)).copy()


def faces_to_cross(faces: npt.ArrayLike) -> np.ndarray:
    """Lay six faces out as the horizontal cross drawn in the module docstring.

    Parameters
    ----------
    faces
        (6, n, n, ...) array in OpenGL face order, rows ↔ t.

    Returns
    -------
    (3n, 4n, ...) array
        Same dtype; the six unused n × n blocks are zero. Row 0 is the top of the picture.
    """
    faces = np.asarray(faces)
    if faces.ndim < 3 or faces.shape[0] != 6 or faces.shape[1] != faces.shape[2]:
        raise ValueError(f"cube faces must have shape (6, n, n, ...), got {faces.shape}")
    n = faces.shape[1]
    cross = np.zeros((3 * n, 4 * n, *faces.shape[3:]), dtype=faces.dtype)
    for face, (row, col) in _CROSS_BLOCKS.items():
        cross[row * n : (row + 1) * n, col * n : (col + 1) * n] = faces[face]
    return cross


def cross_to_faces(cross: npt.ArrayLike) -> np.ndarray:
    """Cut a horizontal cross (:func:`faces_to_cross` layout) into six faces.

    Parameters
    ----------
    cross
        (3n, 4n, ...) array, row 0 at the top.

    Returns
    -------
    (6, n, n, ...) array
        OpenGL face order, rows ↔ t.
    """
    cross = np.asarray(cross)
    if cross.ndim < 2 or cross.shape[0] % 3 or 3 * cross.shape[1] != 4 * cross.shape[0]:
        raise ValueError(f"a cube cross must have shape (3n, 4n, ...), got {cross.shape}")
    n = cross.shape[0] // 3
    blocks = [_CROSS_BLOCKS[face] for face in range(6)]
    return np.stack([cross[r * n : (r + 1) * n, c * n : (c + 1) * n] for r, c in blocks])


def _centres(size: int) -> npt.NDArray[np.float64]:
    if size < 1:
        raise ValueError(f"cube face size must be positive, got {size}")
    return (np.arange(size) + 0.5) / size
