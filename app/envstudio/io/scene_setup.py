"""Building the scene a command asked for: ``--scene``, ``--env``, ``--mesh``, ``--camera``."""

from __future__ import annotations

import math
import os
from pathlib import Path

from envstudio.errors import ParameterError
from envstudio.io.images import read_environment
from envstudio.io.meshes import load_mesh
from envstudio.io.scene_file import load_scene
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene

DEFAULT_SCENE = "studio"


def build_scene(
    scene: str | os.PathLike | None = None,
    env: str | os.PathLike | None = None,
    mesh: str | os.PathLike | None = None,
    max_env_width: int | None = None,
) -> Scene:
    """Load ``scene`` (default ``studio``), then replace its environment and/or reflector.

    A replacement mesh is centred and fitted into the unit sphere and keeps
    the first reflector's material; an environment wider than ``max_env_width``
    is box-filtered as it is read.
    """
    if env is not None:
        read = read_environment(env, max_env_width)
        result = load_scene(scene or DEFAULT_SCENE)
        result.environment = Environment(read, Path(env))
    else:
        result = load_scene(scene or DEFAULT_SCENE, max_env_width)
    if mesh is not None:
        result.nodes = [
            *replace_reflector(result, load_mesh(mesh).fitted(1.0)),
        ]
    replaced = [f"{what} {Path(p).name}" for what, p in (("env", env), ("mesh", mesh)) if p]
    result.variant = ", ".join(replaced)
    return result


def replace_reflector(scene: Scene, mesh) -> list[Node]:
    """The scene's nodes with all reflectors replaced by one node of ``mesh``."""
    reflectors = scene.reflectors()
    material = reflectors[0].material if reflectors else None
    node = Node(mesh.name, mesh, material) if material else Node(mesh.name, mesh)
    return [node, *scene.local_objects()]


def parse_size(text: str) -> tuple[int, int]:
    """``"640x480"`` → (640, 480); raises ParameterError."""
    width, sep, height = text.lower().partition("x")
    try:
        size = (int(width), int(height))
    except ValueError:
        size = (0, 0)
    if not sep or min(size) < 1 or max(size) > 16384:
        raise ParameterError(f"--size {text!r}: expected WIDTHxHEIGHT, e.g. 640x480")
    return size


def parse_camera(text: str) -> tuple[float, float, float]:
    """``"30,15,3"`` → azimuth, elevation (degrees), distance; raises ParameterError."""
    parts = text.split(",")
    try:
        az, el, dist = (float(p) for p in parts)
    except ValueError:
        raise ParameterError(f"--camera {text!r}: expected AZIMUTH,ELEVATION,DISTANCE") from None
    if not math.isfinite(az) or not -90.0 <= el <= 90.0 or not 0.0 < dist < 1e30:
        raise ParameterError(
            f"--camera {text!r}: expected a finite azimuth, elevation in [-90, 90] and a "
            "finite distance > 0"
        )
    return az, el, dist


def subdivide_reflectors(scene: Scene, min_triangles: int) -> None:
    """Subdivide every reflector (midpoint, 4× per step) to at least ``min_triangles`` in all."""
    import trimesh

    from envstudio.scene.mesh import MeshData

    def total() -> int:
        return sum(n.mesh.triangle_count for n in scene.reflectors())

    while total() < min_triangles:
        for node in scene.reflectors():
            mesh = trimesh.Trimesh(node.mesh.positions, node.mesh.indices, process=False)
            vertices, faces = trimesh.remesh.subdivide(mesh.vertices, mesh.faces)
            fine = trimesh.Trimesh(vertices, faces, process=True)
            node.mesh = MeshData(fine.vertices, fine.vertex_normals, fine.faces, node.mesh.name)
