"""The icosahedral view sampling of seed 002 and its spherical barycentric weights.

Seed 002 §3.1 bakes one radiance environment map per view direction at the 12
vertices of an icosahedron ("its symmetry means that each viewpoint is handled
in an unbiased manner"); §3.4 blends the three maps of the face that contains
the current view direction v_d with spherical barycentric weights. §4 reads the
"geodesic locations" and "triangle faces" from the bake, so nothing here is
tied to 12 views: :func:`subdivide` gives the 42 vertices of the once-subdivided
icosahedron, and every function takes any (vertices, faces) pair.

Vertices are the cyclic permutations of (0, ±1, ±φ), normalized (φ the golden
ratio); none lies on ±Y, so every vertex has a camera frame with +Y as up
(core.rsibr_warp.view_frame). Faces are wound counter-clockwise seen from
outside: det(a, b, c) > 0.

Face lookup. A direction d lies in face (a, b, c) when it is on the inner side of
the three great circles through its edges: d · (a × b) ≥ 0, d · (b × c) ≥ 0,
d · (c × a) ≥ 0 (unit edge normals). A direction on a shared edge or vertex lies in
several faces; :func:`find_face` returns the one with the lowest index among those
that contain it to within ``EDGE_TOLERANCE``, so every direction gets exactly
one face and the tie rule does not depend on which side it was approached from.

Spherical barycentrics (§3.4, Figure 2). v_d splits the face (v_0, v_1, v_2) into
three inner triangles; the weight of v_i is the area a_i of the triangle
opposite it, (v_d, v_(i+1)⊘3, v_(i−1)⊘3), over a_0 + a_1 + a_2. On the unit sphere
the area is the spherical excess (§3.4)

    a_i = α_i + β_i + γ_i − π,

with the angles of that triangle at v_(i−1)⊘3, v_(i+1)⊘3 and v_d (§3.4; ⊗ the
normalized cross product)

    α_i = acos((v_d ⊗ v_(i−1)⊘3) · (v_(i+1)⊘3 ⊗ v_(i−1)⊘3))
    β_i = acos((v_(i+1)⊘3 ⊗ v_d) · (v_(i+1)⊘3 ⊗ v_(i−1)⊘3))
    γ_i = acos((v_(i+1)⊘3 ⊗ v_d) · (v_(i−1)⊘3 ⊗ v_d)).

The text extraction of the seed garbled the index-wrapping operator ⊘; from its
use (three vertices, indices i ± 1) it is (§3.4)

    a ⊘ b = b − 1   if a < 0
            0       if a ≥ b
            a       otherwise,

i.e. a mod b for a ∈ [−1, b]: :func:`wrap_index`. The angle form is undefined
when v_d meets a vertex (a zero cross product), exactly where the weights must be
(1, 0, 0), so :func:`spherical_barycentric` evaluates the same excess by Van
Oosterom and Strackee's equivalent tan(E/2) = det(a, b, c) / (1 + a·b + b·c + c·a),
exact at vertices and on edges; :func:`spherical_excess_dihedral` is the paper's
form, and the tests check that the two agree.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = [
    "EDGE_TOLERANCE",
    "face_centres",
    "find_face",
    "icosahedron",
    "spherical_barycentric",
    "spherical_excess",
    "spherical_excess_dihedral",
    "subdivide",
    "view_weights",
    "wrap_index",
]

#: How far outside a face's edge planes (|d · edge normal|, ~radians) still counts as inside.
EDGE_TOLERANCE = 1e-9


def icosahedron() -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int32]]:
    """The 12 unit vertices and 20 counter-clockwise faces of the icosahedron (§3.1).

    Returns
    -------
    vertices : (12, 3) float64
        Unit vectors, world space: the cyclic permutations of (0, ±1, ±φ), normalized.
    faces : (20, 3) int32
        Vertex indices, counter-clockwise seen from outside (det(a, b, c) > 0).
    """
    phi = (1.0 + np.sqrt(5.0)) / 2.0
    vertices = []
    for a in (-1.0, 1.0):
        for b in (-phi, phi):
            vertices += [(0.0, a, b), (a, b, 0.0), (b, 0.0, a)]
    v = np.asarray(vertices) / np.hypot(1.0, phi)
    return v, _faces_of(v, edge=2.0 / np.hypot(1.0, phi))


def subdivide(
    vertices: npt.ArrayLike, faces: npt.ArrayLike
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int32]]:
    """Split every face into four at its edges' midpoints, pushed onto the sphere.

    Parameters
    ----------
    vertices : (V, 3) float
        Unit vectors.
    faces : (F, 3) int
        Counter-clockwise faces.

    Returns
    -------
    vertices : (V + E, 3) float64
        The old vertices first, then one per edge (42 for the icosahedron).
    faces : (4F, 3) int32
        Counter-clockwise.
    """
    v = [tuple(x) for x in np.asarray(vertices, dtype=np.float64)]
    midpoint: dict[tuple[int, int], int] = {}

    def mid(i: int, j: int) -> int:
        key = (min(i, j), max(i, j))
        if key not in midpoint:
            m = np.add(v[i], v[j])
            v.append(tuple(m / np.linalg.norm(m)))
            midpoint[key] = len(v) - 1
        return midpoint[key]

    out = []
    for a, b, c in np.asarray(faces):
        ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
        out += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
    return np.asarray(v), np.asarray(out, dtype=np.int32)


def face_centres(vertices: npt.ArrayLike, faces: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """(F, 3) float64 unit directions through the faces' centroids."""
    v = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)]
    c = v.sum(axis=1)
    return c / np.linalg.norm(c, axis=-1, keepdims=True)


def wrap_index(a: int, b: int) -> int:
    """Seed 002 §3.4's index-wrapping operator a ⊘ b (module docstring), a ∈ [−1, b]."""
    if a < 0:
        return b - 1
    if a >= b:
        return 0
    return a


def find_face(
    directions: npt.ArrayLike, vertices: npt.ArrayLike, faces: npt.ArrayLike
) -> npt.NDArray[np.int64]:
    """The face containing each direction; on an edge or vertex, the lowest such index.

    Parameters
    ----------
    directions : (..., 3) float
        World-space directions, any non-zero length.
    vertices : (V, 3) float
        Unit vertices.
    faces : (F, 3) int
        Counter-clockwise faces covering the sphere.

    Returns
    -------
    (...) int64
        Face index per direction (module docstring: "Face lookup").
    """
    d = np.asarray(directions, dtype=np.float64)
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    inside = _edge_distances(d, vertices, faces).min(axis=-1) >= -EDGE_TOLERANCE
    if not np.all(inside.any(axis=-1)):
        raise ValueError("the faces do not cover the sphere")
    return np.argmax(inside, axis=-1)


def spherical_excess(a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike) -> np.ndarray:
    """Signed area of spherical triangles (a, b, c) on the unit sphere, steradians.

    Van Oosterom–Strackee: tan(E/2) = det(a, b, c) / (1 + a·b + b·c + c·a); positive
    for counter-clockwise triangles, 0 for degenerate ones (module docstring).

    Parameters
    ----------
    a, b, c : (..., 3) float
        Unit vectors.

    Returns
    -------
    (...) float64
    """
    a, b, c = (np.asarray(x, dtype=np.float64) for x in (a, b, c))
    det = np.einsum("...i,...i->...", a, np.cross(b, c))
    dots = 1.0 + np.einsum("...i,...i->...", a, b)
    dots = dots + np.einsum("...i,...i->...", b, c) + np.einsum("...i,...i->...", c, a)
    return 2.0 * np.arctan2(det, dots)


def spherical_excess_dihedral(v_d: npt.ArrayLike, triangle: npt.ArrayLike, i: int) -> float:
    """Seed 002 §3.4's a_i = α_i + β_i + γ_i − π, literally (for checking).

    Parameters
    ----------
    v_d : (3,) float
        Unit view direction strictly inside the triangle (not on a vertex).
    triangle : (3, 3) float
        Unit vertices v_0, v_1, v_2.
    i
        Which inner triangle: the one opposite v_i.

    Returns
    -------
    float
        Its area, steradians.
    """
    v = np.asarray(triangle, dtype=np.float64)
    d = np.asarray(v_d, dtype=np.float64)
    prev, nxt = v[wrap_index(i - 1, 3)], v[wrap_index(i + 1, 3)]

    def ncross(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        c = np.cross(x, y)
        return c / np.linalg.norm(c)

    def angle(x: np.ndarray, y: np.ndarray) -> float:
        return float(np.arccos(np.clip(np.dot(x, y), -1.0, 1.0)))

    alpha = angle(ncross(d, prev), ncross(nxt, prev))
    beta = angle(ncross(nxt, d), ncross(nxt, prev))
    gamma = angle(ncross(nxt, d), ncross(prev, d))
    return alpha + beta + gamma - np.pi


def spherical_barycentric(v_d: npt.ArrayLike, triangle: npt.ArrayLike) -> np.ndarray:
    """Seed 002 §3.4's weights of the three vertices of a spherical triangle for v_d.

    Parameters
    ----------
    v_d : (..., 3) float
        Unit directions inside the triangle (or on its boundary).
    triangle : (..., 3, 3) float
        Unit vertices v_0, v_1, v_2, counter-clockwise.

    Returns
    -------
    (..., 3) float64
        a_i / (a_0 + a_1 + a_2) with a_i the area of (v_d, v_(i+1)⊘3, v_(i−1)⊘3),
        clipped at 0 (and to exactly 0 under 1e-12 of the sum, so a vertex gets
        exactly (1, 0, 0)); non-negative, summing to 1.
    """
    d = np.asarray(v_d, dtype=np.float64)
    v = np.asarray(triangle, dtype=np.float64)
    areas = np.stack(
        [
            spherical_excess(d, v[..., wrap_index(i + 1, 3), :], v[..., wrap_index(i - 1, 3), :])
            for i in range(3)
        ],
        axis=-1,
    )
    areas = np.maximum(areas, 0.0)
    total = areas.sum(axis=-1, keepdims=True)
    areas = np.where(areas < 1e-12 * total, 0.0, areas)  # rounding at a vertex or an edge
    return areas / areas.sum(axis=-1, keepdims=True)


def view_weights(
    v_d: npt.ArrayLike, vertices: npt.ArrayLike, faces: npt.ArrayLike
) -> tuple[int, npt.NDArray[np.int32], npt.NDArray[np.float64]]:
    """§4's FindSubtendedTriangle and ComputeWeights for one view direction.

    Parameters
    ----------
    v_d : (3,) float
        World-space direction toward the viewer (the destination map's +z).
    vertices : (V, 3) float
        Unit view directions of the baked maps.
    faces : (F, 3) int
        Counter-clockwise faces.

    Returns
    -------
    face : int
        Index of the face containing v_d (:func:`find_face`).
    indices : (3,) int32
        Its vertices (the maps to blend).
    weights : (3,) float64
        Their spherical barycentric weights (:func:`spherical_barycentric`).
    """
    d = np.asarray(v_d, dtype=np.float64)
    d = d / np.linalg.norm(d)
    face = int(find_face(d, vertices, faces))
    indices = np.asarray(faces)[face].astype(np.int32)
    weights = spherical_barycentric(d, np.asarray(vertices, dtype=np.float64)[indices])
    return face, indices, weights


def _edge_distances(d: np.ndarray, vertices: npt.ArrayLike, faces: npt.ArrayLike) -> np.ndarray:
    """(..., F, 3) d · unit normal of each face's three edge planes (inside ≥ 0)."""
    v = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)]
    normals = np.cross(v, np.roll(v, -1, axis=1))
    normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
    return np.einsum("...k,fek->...fe", d, normals)


def _faces_of(v: np.ndarray, edge: float) -> np.ndarray:
    """Counter-clockwise triangles of mutually adjacent vertices (edge length ``edge``)."""
    n = len(v)
    near = np.isclose(np.linalg.norm(v[:, None] - v[None], axis=-1), edge)
    faces = []
    for i in range(n):
        for j in range(i + 1, n):
            for k in range(j + 1, n):
                if near[i, j] and near[j, k] and near[i, k]:
                    tri = (i, j, k) if np.linalg.det(v[[i, j, k]]) > 0 else (i, k, j)
                    faces.append(tri)
    return np.asarray(faces, dtype=np.int32)
