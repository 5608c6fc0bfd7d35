"""A bounding volume hierarchy over triangles, flattened for GPU traversal.

Built top-down by splitting at the median centroid along the longest axis of
the centroid bounds, down to leaves of at most ``leaf_size`` triangles. Nodes
are stored depth first, so an interior node's left child is the next node and
only the right child's index is stored. Triangles are reordered so each leaf
is a contiguous range. shaders/reference/trace.glsl walks the same layout; a
NumPy traversal (:func:`intersect`) is the CPU twin used by tests, which check
both against Embree.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt


@dataclass
class FlatBVH:
    """Depth-first BVH arrays.

    Attributes
    ----------
    bounds_min, bounds_max : (k, 3) float32
        Node boxes.
    right_or_first : (k,) int32
        Interior: index of the right child; leaf: first triangle.
    count : (k,) int32
        Leaf: number of triangles (> 0); interior: 0.
    order : (m,) int64
        Triangle index (into the input) of each position in the reordered list.
    """

    bounds_min: npt.NDArray[np.float32]
    bounds_max: npt.NDArray[np.float32]
    right_or_first: npt.NDArray[np.int32]
    count: npt.NDArray[np.int32]
    order: npt.NDArray[np.int64]

    @property
    def node_count(self) -> int:
        """Number of nodes."""
        return len(self.count)

    @property
    def depth(self) -> int:
        """Edges on the longest path from the root to a leaf (0 for a single leaf)."""
        deepest = 0
        stack = [(0, 0)]
        while stack:
            node, level = stack.pop()
            if self.count[node] > 0:
                deepest = max(deepest, level)
            else:
                stack += [(node + 1, level + 1), (int(self.right_or_first[node]), level + 1)]
        return deepest


def build_bvh(triangles: npt.ArrayLike, leaf_size: int = 4) -> FlatBVH:
    """Build a BVH over (m, 3, 3) triangle vertex positions."""
    tris = np.asarray(triangles, dtype=np.float64)
    if tris.ndim != 3 or tris.shape[1:] != (3, 3) or len(tris) == 0:
        raise ValueError(f"triangles must have shape (m, 3, 3) with m > 0, got {tris.shape}")
    lo_tri, hi_tri = tris.min(axis=1), tris.max(axis=1)
    centroids = tris.mean(axis=1)
    mins, maxs, links, counts, order = [], [], [], [], []
    stack = [(np.arange(len(tris)), None)]  # (triangle ids, parent waiting for its right child)
    while stack:
        ids, parent = stack.pop()
        node = len(counts)
        if parent is not None:
            links[parent] = node
        mins.append(lo_tri[ids].min(axis=0))
        maxs.append(hi_tri[ids].max(axis=0))
        if len(ids) <= leaf_size:
            links.append(len(order))
            counts.append(len(ids))
            order.extend(ids.tolist())
            continue
        c = centroids[ids]
        axis = int(np.argmax(c.max(axis=0) - c.min(axis=0)))
        sorted_ids = ids[np.argsort(c[:, axis], kind="stable")]
        half = len(ids) // 2
        links.append(-1)
        counts.append(0)
        stack.append((sorted_ids[half:], node))  # right child: popped after the left subtree
        stack.append((sorted_ids[:half], None))  # left child: the very next node
    return FlatBVH(
        np.array(mins, dtype=np.float32),
        np.array(maxs, dtype=np.float32),
        np.array(links, dtype=np.int32),
        np.array(counts, dtype=np.int32),
        np.array(order, dtype=np.int64),
    )


def intersect(
    bvh: FlatBVH, triangles: npt.ArrayLike, origin: npt.ArrayLike, direction: npt.ArrayLike
) -> tuple[float, int]:
    """Closest hit of one ray (CPU twin of trace.glsl), by Möller–Trumbore.

    Returns
    -------
    t, triangle
        Distance along ``direction`` and the input triangle index, or (inf, -1).
    """
    tris = np.asarray(triangles, dtype=np.float64)[bvh.order]
    o = np.asarray(origin, dtype=np.float64)
    d = np.asarray(direction, dtype=np.float64)
    inv = 1.0 / np.where(d == 0.0, 1e-30, d)
    best_t, best = np.inf, -1
    stack = [0]
    while stack:
        node = stack.pop()
        t0 = (bvh.bounds_min[node] - o) * inv
        t1 = (bvh.bounds_max[node] - o) * inv
        near = np.minimum(t0, t1).max()
        far = np.maximum(t0, t1).min()
        if far < max(near, 0.0) or near > best_t:
            continue
        if bvh.count[node] > 0:
            first = bvh.right_or_first[node]
            for k in range(first, first + bvh.count[node]):
                t = _ray_triangle(o, d, tris[k])
                if t < best_t:
                    best_t, best = t, int(bvh.order[k])
        else:
            stack += [int(bvh.right_or_first[node]), node + 1]
    return best_t, best


def _ray_triangle(o, d, tri) -> float:
    e1, e2 = tri[1] - tri[0], tri[2] - tri[0]
    p = np.cross(d, e2)
    det = e1 @ p
    if abs(det) < 1e-12:
        return np.inf
    s = o - tri[0]
    u = (s @ p) / det
    q = np.cross(s, e1)
    v = (d @ q) / det
    t = (e2 @ q) / det
    if u < 0 or v < 0 or u + v > 1 or t <= 1e-6:
        return np.inf
    return float(t)
