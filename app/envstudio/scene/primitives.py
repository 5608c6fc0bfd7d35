"""Procedural meshes: UV sphere, box, an inward-facing room, and a (p, q) torus knot."""

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


def torus_knot(
    p: int = 2,
    q: int = 3,
    radius: float = 1.0,
    tube: float = 0.4,
    segments: int = 160,
    sides: int = 13,
) -> MeshData:
    """A closed tube of radius ``tube`` about the (p, q) torus knot, smooth normals.

    The knot curve (as three.js's ``TorusKnotGeometry`` draws it) winds p
    times about the z axis and q times through the torus' hole:
    c(u) = radius / 2 · ((2 + cos(qu/p)) cos u, (2 + cos(qu/p)) sin u, sin(qu/p)),
    u ∈ [0, 2πp). The tube's ring at c(u) lies in the plane normal to the
    curve, in a frame rotated along the curve by parallel transport (the
    rings' twist over the whole loop is spread evenly, so the last ring meets
    the first), and its normals are the exact ones of the tube, (x − c) /
    tube. ``segments`` × ``sides`` quads, 2 · segments · sides triangles
    (4160 at the defaults), counter-clockwise seen from outside. A strongly
    self-occluding, concave closed surface: the strands pass within about
    one tube diameter of one another.
    """
    u = np.arange(segments) / segments * 2.0 * np.pi * p

    def curve(u):
        phase = q / p * u
        ring = 2.0 + np.cos(phase)
        return 0.5 * radius * np.stack([ring * np.cos(u), ring * np.sin(u), np.sin(phase)], -1)

    centres = curve(u)
    step = 1e-4
    tangent = curve(u + step) - curve(u - step)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    # parallel transport of a normal along the closed curve
    frame = np.empty((segments, 3))
    start = np.cross(tangent[0], (0.0, 0.0, 1.0))
    frame[0] = start / np.linalg.norm(start)
    for k in range(1, segments + 1):
        previous = frame[k - 1]
        t = tangent[k % segments]
        moved = previous - (previous @ t) * t
        moved /= np.linalg.norm(moved)
        if k < segments:
            frame[k] = moved
    # the twist the transport left after one loop, undone evenly along it
    binormal0 = np.cross(tangent[0], frame[0])
    twist = np.arctan2(moved @ binormal0, moved @ frame[0])
    angles = -twist * np.arange(segments) / segments
    binormal = np.cross(tangent, frame)
    normal = np.cos(angles)[:, None] * frame + np.sin(angles)[:, None] * binormal
    binormal = np.cross(tangent, normal)
    around = np.arange(sides) / sides * 2.0 * np.pi
    normals = (
        np.cos(around)[None, :, None] * normal[:, None, :]
        + np.sin(around)[None, :, None] * binormal[:, None, :]
    )
    positions = centres[:, None, :] + tube * normals
    i, j = np.meshgrid(np.arange(segments), np.arange(sides), indexing="ij")
    a = (i * sides + j).ravel()
    b = (((i + 1) % segments) * sides + j).ravel()
    c = (i * sides + (j + 1) % sides).ravel()
    d = (((i + 1) % segments) * sides + (j + 1) % sides).ravel()
    tris = np.concatenate([np.stack([a, c, b], 1), np.stack([c, d, b], 1)])
    name = f"torus_knot(p={p}, q={q}, tube={tube})"
    return MeshData(positions.reshape(-1, 3), normals.reshape(-1, 3), tris, name)
