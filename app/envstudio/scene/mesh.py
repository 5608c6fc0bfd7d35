"""Triangle meshes as plain arrays (no GL)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt


@dataclass
class MeshData:
    """An indexed triangle mesh.

    Attributes
    ----------
    positions : (n, 3) float32
        Vertex positions in the mesh's own units.
    normals : (n, 3) float32
        Unit vertex normals.
    indices : (m, 3) uint32
        Counter-clockwise triangles.
    name : str
        Where the mesh came from (file name or primitive), for messages.
    uvs : (n, 2) float32 or None
        Texture coordinates per vertex, if the mesh has them (the ``uv`` tangent
        field of scene/tangents.py follows their u direction).
    """

    positions: npt.NDArray[np.float32]
    normals: npt.NDArray[np.float32]
    indices: npt.NDArray[np.uint32]
    name: str = "mesh"
    uvs: npt.NDArray[np.float32] | None = None

    def __post_init__(self):
        self.positions = np.ascontiguousarray(self.positions, dtype=np.float32).reshape(-1, 3)
        self.normals = np.ascontiguousarray(self.normals, dtype=np.float32).reshape(-1, 3)
        self.indices = np.ascontiguousarray(self.indices, dtype=np.uint32).reshape(-1, 3)
        if len(self.normals) != len(self.positions):
            raise ValueError(f"{self.name}: {len(self.normals)} normals for {len(self.positions)}")
        if self.uvs is not None:
            self.uvs = np.ascontiguousarray(self.uvs, dtype=np.float32).reshape(-1, 2)
            if len(self.uvs) != len(self.positions):
                raise ValueError(f"{self.name}: {len(self.uvs)} uvs for {len(self.positions)}")

    @property
    def triangle_count(self) -> int:
        """Number of triangles."""
        return len(self.indices)

    def bounds(self) -> npt.NDArray[np.float32]:
        """(2, 3) minimum and maximum corner."""
        return np.stack([self.positions.min(axis=0), self.positions.max(axis=0)])

    def tangents(self) -> npt.NDArray[np.float32]:
        """(n, 3) unit tangents orthogonal to the normals, for anisotropic materials.

        Without texture coordinates the tangent follows the direction of
        increasing azimuth about +Y (``up × n``), falling back to +X at the poles.
        """
        n = self.normals.astype(np.float64)
        t = np.cross((0.0, 1.0, 0.0), n)
        pole = np.linalg.norm(t, axis=1) < 1e-6
        t[pole] = np.cross(n[pole], (0.0, 0.0, 1.0))
        return (t / np.linalg.norm(t, axis=1, keepdims=True)).astype(np.float32)

    def fitted(self, radius: float = 1.0) -> MeshData:
        """A copy centred on its bounding box and scaled into a sphere of ``radius``."""
        lo, hi = self.bounds()
        centre = (lo + hi) / 2
        extent = np.linalg.norm(self.positions - centre, axis=1).max()
        scale = radius / extent if extent > 0 else 1.0
        return MeshData(
            (self.positions - centre) * scale, self.normals, self.indices, self.name, self.uvs
        )


def loop_subdivided(mesh: MeshData, steps: int) -> MeshData:
    """``mesh`` after ``steps`` Loop subdivisions (4× the triangles each; normals recomputed).

    Loop's scheme smooths towards the limit surface (it moves the original
    vertices), so a coarse mesh such as the teapot gets the smooth surface the
    PEM bake's close views need (seed 003 §6: ~40k triangles).

    Parameters
    ----------
    mesh
        The mesh; its UVs are dropped (Loop's scheme does not carry them here).
    steps
        Subdivision steps, ≥ 1.
    """
    import trimesh

    vertices, faces = trimesh.remesh.subdivide_loop(mesh.positions, mesh.indices, iterations=steps)
    fine = trimesh.Trimesh(vertices, faces, process=True)
    normals = np.asarray(fine.vertex_normals, dtype=np.float32)
    return MeshData(fine.vertices, normals, fine.faces, mesh.name)
