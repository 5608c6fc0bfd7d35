"""Procedural meshes: UV sphere, box, and an inward-facing room."""

from __future__ import annotations

import numpy as np

from envstudio.scene.mesh import MeshData


def uv_sphere(radius: float = 1.0, rings: int = 48, segments: int = 96) -> MeshData:
    """A UV sphere centred at the origin with exact analytic normals."""
    theta = np.linspace(0.0, np.pi, rings + 1)
    phi = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    normals = np.stack([np.sin(t) * np.sin(p), np.cos(t), np.sin(t) * np.cos(p)], axis=-1)
    normals = normals.reshape(-1, 3)
    r, s = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    a = (r * (segments + 1) + s).ravel()
    b, c, d = a + segments + 1, a + 1, a + segments + 2
    tris = np.concatenate([np.stack([a, b, c], 1), np.stack([c, b, d], 1)])
    uvs = np.stack([p / (2.0 * np.pi), 1.0 - t / np.pi], axis=-1).reshape(-1, 2)
    return MeshData(normals * radius, normals, tris, f"sphere(r={radius})", uvs)


def box(size: float = 1.0, inward: bool = False) -> MeshData:
    """An axis-aligned cube of edge ``size`` centred at the origin, flat normals.

    With ``inward`` the faces (winding and normals) point into the box, as the
    walls of a room seen from inside.
    """
    positions, normals, tris = [], [], []
    for axis in range(3):
        for sign in (1.0, -1.0):
            n = np.zeros(3)
            n[axis] = sign
            u = np.zeros(3)
            u[(axis + 1) % 3] = 1.0
            v = np.cross(n, u)
            base = len(positions)
            for du, dv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                positions.append((n + du * u + dv * v) * size / 2)
                normals.append(-n if inward else n)
            quad = [(0, 1, 2), (0, 2, 3)]
            tris += [
                (base + i, base + k, base + j) if inward else (base + i, base + j, base + k)
                for i, j, k in quad
            ]
    return MeshData(
        np.array(positions), np.array(normals), np.array(tris), "room" if inward else f"box({size})"
    )
