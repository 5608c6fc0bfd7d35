"""Mesh files through trimesh (OBJ, PLY, STL, OFF, GLB/glTF)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import trimesh

from envstudio.errors import InputFileError
from envstudio.scene.mesh import MeshData

MESH_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")


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
        Missing file, unknown format, unreadable data, or no faces.
    """
    path = Path(path)
    if not path.is_file():
        raise InputFileError(f"{path}: no such file (expected a mesh: {', '.join(MESH_SUFFIXES)})")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise InputFileError(
            f"{path}: unknown mesh type, expected one of {', '.join(MESH_SUFFIXES)}"
        )
    try:
        loaded = trimesh.load(str(path), force="mesh")
    except Exception as exc:
        raise InputFileError(f"{path}: cannot read mesh ({type(exc).__name__}: {exc})") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise InputFileError(f"{path}: mesh has no faces, expected triangles")
    mesh = loaded
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
