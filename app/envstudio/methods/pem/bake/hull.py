"""The convex-hull split of a reflector's triangles and the mesh check (seed 003 §4).

Seed 003 §4 ("Layered EMs"): "we minimize such problems by separating polygons
on the reflector that lie on its convex hull from those lying inside it as a
view-independent pre-process. At run-time, polygons lying on the convex hull are
rendered only with the distant EM, since they can never exhibit
self-reflections." :func:`hull_mask` marks, per triangle of a part's mesh (in
its faces' order, the order the playback draws them), whether it lies on the
part's convex hull: all three corners within ``tol`` of one hull facet's plane
(world space, scipy.spatial.ConvexHull) and its geometric normal parallel to
that facet's (|cos| ≥ ``cos_tol``; either winding). A vertex in a supporting
plane of the hull lies on the hull, so this is "the triangle is part of the
hull's boundary".

:func:`mesh_check` identifies the mesh a bake was made for, so the playback
can refuse a ``.pem`` for another one.

The hull of a bake (:func:`reflector_hulls`) is that of *all* the reflector
parts together, each part's mask marking its triangles on it: the local layer
holds reflections of any part (the lid in the body, the body in the lid), so a
triangle on its own part's hull can still show one, while a triangle on the
hull of the union cannot. With one part the two are the same.
"""

from __future__ import annotations

import hashlib

import numpy as np
import numpy.typing as npt

from envstudio.scene.graph import Node

__all__ = ["hull_mask", "mesh_check", "node_world_mesh", "reflector_hulls"]


def node_world_mesh(node: Node) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.int32]]:
    """A node's world-space vertices (n, 3) float32 and its faces (m, 3) int32."""
    model = node.transform.matrix().astype(np.float64)
    world = node.mesh.positions.astype(np.float64) @ model[:3, :3].T + model[:3, 3]
    return world.astype(np.float32), np.asarray(node.mesh.indices, dtype=np.int32)


def mesh_check(node: Node) -> dict:
    """``{"name", "vertices", "triangles", "sha256"}`` of a node's mesh where it stands.

    ``sha256`` is the SHA-256 of the mesh's float32 vertex bytes (n, 3) as loaded
    (object space), its int32 face bytes (m, 3) (C order, little-endian), then
    the node's model matrix printed to 6 decimals: the same on every machine,
    where a world-space product's last bits may differ between BLAS builds.
    """
    vertices = np.ascontiguousarray(node.mesh.positions, dtype="<f4")
    faces = np.ascontiguousarray(node.mesh.indices, dtype="<i4")
    digest = hashlib.sha256(vertices.tobytes())
    digest.update(faces.tobytes())
    model = np.asarray(node.transform.matrix(), dtype=np.float64) + 0.0  # no -0.0
    digest.update(" ".join(f"{x:.6f}" for x in np.round(model, 6).ravel()).encode())
    return {
        "name": node.name,
        "vertices": len(vertices),
        "triangles": len(faces),
        "sha256": digest.hexdigest(),
    }


def hull_mask(
    vertices: npt.ArrayLike,
    faces: npt.ArrayLike,
    tol: float = 1e-5,
    cos_tol: float = 0.999,
    hull_points: npt.ArrayLike | None = None,
) -> npt.NDArray[np.bool_]:
    """(m,) bool: the triangles lying on the convex hull of the mesh (module docstring).

    Parameters
    ----------
    vertices
        (n, 3) float world-space positions.
    faces
        (m, 3) int corner indices.
    tol
        Distance to a facet plane, relative to the mesh's bounding-box diagonal.
    cos_tol
        Least |cos| between the triangle's normal and the facet's.
    hull_points
        (k, 3) points whose hull is taken (default ``vertices``): all the
        reflectors' vertices for :func:`reflector_hulls`.

    Returns
    -------
    (m,) bool
        All False for a flat or degenerate mesh (no 3D hull).
    """
    from scipy.spatial import ConvexHull, QhullError

    v = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    out = np.zeros(len(f), dtype=bool)
    if len(f) == 0:
        return out
    pts = v if hull_points is None else np.asarray(hull_points, dtype=np.float64).reshape(-1, 3)
    try:
        hull = ConvexHull(pts)
    except (QhullError, ValueError):
        return out
    planes = np.unique(np.round(hull.equations, 9), axis=0)  # (F, 4): n·x + d ≤ 0 inside
    scale = float(np.linalg.norm(np.ptp(pts, axis=0))) or 1.0
    corners = v[f]  # (m, 3, 3)
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(normal, axis=1)
    unit = normal / np.where(length > 0, length, 1.0)[:, None]
    degenerate = length <= 1e-10 * scale * scale

    def on_facets(rows: np.ndarray, facets: np.ndarray) -> np.ndarray:
        """Whether triangle rows[i]'s corners all lie within tol of facet facets[i]'s plane."""
        plane = planes[facets]
        dist = np.einsum("kcx,kx->kc", corners[rows], plane[:, :3]) + plane[:, 3:4]
        return np.all(np.abs(dist) <= tol * scale, axis=1)

    # A facet can hold a non-degenerate triangle only if its normal is within the angle
    # of cos_tol of ± the triangle's: found by a KD-tree over the facets' unit normals
    # (chord² = 2 − 2 cos), then tested exactly; m × F tests took 2 min for 63k triangles.
    from scipy.spatial import cKDTree

    tree = cKDTree(planes[:, :3])
    chord = np.sqrt(max(2.0 - 2.0 * cos_tol, 0.0)) * (1.0 + 1e-6) + 1e-12
    solid = np.flatnonzero(~degenerate)
    for sign in (1.0, -1.0):
        near = tree.query_ball_point(sign * unit[solid], chord)
        counts = np.fromiter((len(n) for n in near), dtype=np.int64, count=len(near))
        if not counts.any():
            continue
        rows = np.repeat(solid, counts)
        facets = np.concatenate([np.asarray(n, dtype=np.int64) for n in near if n])
        parallel = np.abs(np.einsum("kx,kx->k", unit[rows], planes[facets, :3])) >= cos_tol
        hit = parallel & on_facets(rows, facets)
        out[rows[hit]] = True
    # degenerate triangles (no normal): on the hull if on any facet's plane
    for row in np.flatnonzero(degenerate):
        out[row] = on_facets(np.full(len(planes), row), np.arange(len(planes))).any()
    return out


def reflector_hulls(scene) -> list[npt.NDArray[np.bool_]]:
    """Per reflector part (scene order), (T_p,) bool: its triangles on the reflectors' hull."""
    meshes = [node_world_mesh(node) for node in scene.reflectors()]
    if not meshes:
        return []
    points = np.concatenate([v for v, _ in meshes])
    return [hull_mask(v, f, hull_points=points) for v, f in meshes]
