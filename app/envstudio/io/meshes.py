"""Mesh files through trimesh (OBJ, PLY, STL, OFF, GLB/glTF)."""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import trimesh

from envstudio.errors import InputFileError
from envstudio.scene.mesh import MeshData

MESH_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")
#: Coordinates past this are out of range (their squares overflow float32 on the GPU).
MAX_COORDINATE = 1e15
#: A triangle whose area is below this fraction of the mesh's bounding box face is degenerate.
DEGENERATE_AREA = 1e-12


def load_mesh(path: str | os.PathLike, components: Sequence[int] | None = None) -> MeshData:
    """Load a triangle mesh; scenes are flattened into one mesh in world units.

    Vertex normals are taken from the file or computed (area-weighted) where
    missing; duplicate vertices are merged so smooth surfaces shade smoothly.

    Parameters
    ----------
    path
        Mesh file.
    components
        Keep only these connected components (indices in trimesh's ``split``
        order), e.g. the lid of the teapot. None keeps everything.

    Raises
    ------
    InputFileError
        Missing file, unknown format, unreadable data, no faces, NaN, Inf or
        out-of-range coordinates, or nothing but degenerate triangles (one with
        some drops them and says how many).
    """
    path = Path(path)
    if not path.is_file():
        raise InputFileError(f"{path}: no such file (expected a mesh: {', '.join(MESH_SUFFIXES)})")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise InputFileError(
            f"{path}: unknown mesh type, expected one of {', '.join(MESH_SUFFIXES)}"
        )
    try:
        loaded = trimesh.load(str(path), force="mesh", process=False)
    except Exception as exc:
        raise InputFileError(f"{path}: cannot read mesh ({type(exc).__name__}: {exc})") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise InputFileError(f"{path}: mesh has no faces, expected triangles")
    mesh = _checked(path, loaded)
    mesh.process()  # merge duplicate vertices (smooth shading), after the checks
    if components is not None:
        parts = mesh.split(only_watertight=False)
        bad = [i for i in components if not 0 <= i < len(parts)]
        if bad:
            raise InputFileError(f"{path}: component {bad[0]} not in 0..{len(parts) - 1}")
        mesh = trimesh.util.concatenate([parts[i] for i in components])
    normals = np.asarray(mesh.vertex_normals, dtype=np.float32)
    uv = getattr(mesh.visual, "uv", None)
    uvs = None if uv is None or len(uv) != len(mesh.vertices) else np.asarray(uv, np.float32)
    return MeshData(mesh.vertices, normals, mesh.faces, path.name, uvs)


def _checked(path: Path, mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """``mesh`` without its degenerate triangles, or one line saying what is wrong with it."""
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces)
    used = np.unique(faces)
    bad = ~np.isfinite(vertices[used]).all(axis=1)
    if bad.any():
        hit = np.isin(faces, used[bad]).any(axis=1)
        raise InputFileError(
            f"{path}: {int(bad.sum())} vertices are NaN or Inf ({int(hit.sum())} of "
            f"{len(faces)} faces use them); expected finite coordinates"
        )
    largest = float(np.abs(vertices[used]).max())
    if largest > MAX_COORDINATE:
        raise InputFileError(
            f"{path}: coordinates up to {largest:.3g} are out of range "
            f"(expected at most {MAX_COORDINATE:g} in magnitude)"
        )
    corners = vertices[faces]
    areas = 0.5 * np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    extent = float(np.ptp(vertices[used], axis=0).max())
    degenerate = areas <= DEGENERATE_AREA * extent**2
    if degenerate.all():
        what = "all its vertices coincide" if extent == 0.0 else "every triangle has no area"
        raise InputFileError(
            f"{path}: {what} ({len(faces)} degenerate faces); expected triangles with area"
        )
    if degenerate.any():
        print(
            f"envstudio: note: {path}: {int(degenerate.sum())} of {len(faces)} faces have no "
            "area, dropped",
            file=sys.stderr,
        )
        mesh = mesh.copy()
        mesh.update_faces(~degenerate)
        mesh.remove_unreferenced_vertices()
    return mesh
