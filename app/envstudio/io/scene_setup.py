"""Building the scene a command asked for: ``--scene``, ``--env``, ``--mesh``, ``--camera``,
and the frame ``--size``, checked alike for the command line and the API."""

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


#: The largest frame edge, pixels (``--size`` and the API's ``size``).
MAX_EDGE = 16384


def parse_size(text: str) -> tuple[int, int]:
    """``"640x480"`` → (640, 480); raises ParameterError."""
    width, sep, height = text.lower().partition("x")
    try:
        size = (int(width), int(height)) if sep else (0, 0)
    except ValueError:
        size = (0, 0)
    return check_size(size, f"--size {text!r}", "WIDTHxHEIGHT (e.g. 640x480)")


def check_size(size: tuple[int, int], name: str, form: str) -> tuple[int, int]:
    """``size`` (width, height) when each edge is 1..:data:`MAX_EDGE` pixels.

    Parameters
    ----------
    size
        Width and height as integers.
    name, form
        How the caller calls it and writes it (``--size '0x8'``, ``WIDTHxHEIGHT``).

    Raises
    ------
    ParameterError
        Unless both edges are in range.
    """
    if not all(1 <= edge <= MAX_EDGE for edge in size):
        raise ParameterError(f"{name}: expected {form}, each 1..{MAX_EDGE}")
    return size


def parse_camera(text: str) -> tuple[float, float, float]:
    """``"30,15,3"`` → azimuth, elevation (degrees), distance; raises ParameterError."""
    parts = text.split(",")
    try:
        az, el, dist = (float(p) for p in parts)
    except ValueError:
        raise ParameterError(f"--camera {text!r}: expected AZIMUTH,ELEVATION,DISTANCE") from None
    return check_camera((az, el, dist), f"--camera {text!r}")


def check_camera(camera: tuple[float, float, float], name: str) -> tuple[float, float, float]:
    """``camera`` (azimuth, elevation, distance) when it places an orbit camera.

    Parameters
    ----------
    camera
        Azimuth and elevation in degrees, distance in scene units.
    name
        How the caller calls it (``--camera '0,100,3'``).

    Raises
    ------
    ParameterError
        Unless the azimuth is finite, the elevation in [-90, 90] and the distance in (0, 1e30).
    """
    az, el, dist = camera
    if not math.isfinite(az) or not -90.0 <= el <= 90.0 or not 0.0 < dist < 1e30:
        raise ParameterError(
            f"{name}: expected a finite azimuth, elevation in [-90, 90] and a finite distance > 0"
        )
    return camera


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
