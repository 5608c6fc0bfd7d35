"""What the viewer shows: scene, environment, reflector mesh, object rotation and turntable.

Every load reads the file completely before touching the GPU scene, so a bad
file raises a one-line :class:`~envstudio.errors.UserError` and the previous
scene stays as it was.

The object rotation (XYZ Euler degrees) is added to each reflector's rotation
from the scene file and written to its :class:`~envstudio.scene.graph.Transform`;
the turntable advances its Y angle.
"""

from __future__ import annotations

import os
from pathlib import Path

from envstudio.engine.session import RenderSession
from envstudio.errors import InputFileError
from envstudio.io.images import HDR_SUFFIXES, read_environment
from envstudio.io.meshes import MESH_SUFFIXES, load_mesh
from envstudio.io.scene_file import load_scene, shipped_environments, shipped_scenes
from envstudio.io.scene_setup import DEFAULT_SCENE, replace_reflector
from envstudio.resources import asset_root
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node

Angles = tuple[float, float, float]


def shipped_meshes() -> dict[str, Path]:
    """File name → path for the meshes in ``assets/mesh``."""
    folder = asset_root() / "mesh"
    return {p.name: p for p in sorted(folder.iterdir()) if p.suffix.lower() in MESH_SUFFIXES}


def _wrap_degrees(angle: float) -> float:
    """``angle`` in [-180, 180)."""
    return (angle + 180.0) % 360.0 - 180.0


class SceneControl:
    """Loads scenes, environments and meshes into a session and poses the reflectors.

    Parameters
    ----------
    session
        The session whose GPU scene is changed.
    scene_spec
        Shipped scene name or scene file the session's scene came from.
    scene_reflectors
        The scene file's own reflector nodes (before a mesh replaced them).
    environment, mesh
        Files that replaced the scene's environment / reflectors, or None.

    Attributes
    ----------
    rotation : list of float
        Object rotation, XYZ degrees in [-180, 180).
    turntable : bool
        Whether :meth:`advance` spins the object about +Y.
    turntable_speed : float
        Degrees per second (negative: clockwise seen from above).
    """

    def __init__(
        self,
        session: RenderSession,
        scene_spec: str | None,
        scene_reflectors: list[Node],
        environment: str | os.PathLike | None = None,
        mesh: str | os.PathLike | None = None,
    ):
        self.session = session
        self.scene_spec = scene_spec or DEFAULT_SCENE
        self.environment_path = Path(environment).resolve() if environment else None
        self.mesh_path = Path(mesh).resolve() if mesh else None
        self.rotation = [0.0, 0.0, 0.0]
        self.turntable = False
        self.turntable_speed = 20.0
        self.scenes = shipped_scenes()
        self.environments = shipped_environments()
        self.meshes = shipped_meshes()
        self._scene_reflectors: list[Node] = []
        self._base_rotation: dict[int, Angles] = {}
        self._remember_scene_reflectors(scene_reflectors)

    @property
    def scene_label(self) -> str:
        """Short name of the scene (shipped name or file stem)."""
        return self.session.scene.name

    @property
    def environment_label(self) -> str:
        """Short name of the environment shown."""
        source = self.session.scene.environment.source
        return source.name if source else "procedural"

    @property
    def mesh_label(self) -> str:
        """The replacement mesh's file name, or the scene's own reflectors."""
        return self.mesh_path.name if self.mesh_path else "scene's own"

    def load_scene(self, spec: str) -> None:
        """Show the shipped scene or scene file ``spec`` with its own environment and reflectors.

        The camera moves to the scene's viewpoint; the object rotation is kept.
        """
        scene = load_scene(spec)
        gpu = self.session.gpu_scene
        gpu.scene = scene
        gpu.set_environment(scene.environment)
        gpu.set_nodes(scene.nodes)
        self.session.camera = scene.camera
        self.scene_spec = spec if spec in self.scenes else str(Path(spec).resolve())
        self.environment_path = None
        self.mesh_path = None
        self._remember_scene_reflectors(scene.reflectors())
        self.apply_rotation()

    def load_environment(self, path: str | os.PathLike) -> None:
        """Light the scene with the lat-long map in ``path`` (.exr or .hdr)."""
        path = Path(path).resolve()
        environment = Environment(read_environment(path), path)
        self.session.gpu_scene.set_environment(environment)
        self.environment_path = path

    def load_mesh(self, path: str | os.PathLike | None) -> None:
        """Replace the reflectors by the mesh in ``path`` (fitted into the unit sphere).

        None brings back the scene's own reflectors. The material of the
        scene's first reflector is kept.
        """
        gpu = self.session.gpu_scene
        if path is None:
            nodes = [*self._scene_reflectors, *gpu.scene.local_objects()]
            resolved = None
        else:
            resolved = Path(path).resolve()
            nodes = replace_reflector(gpu.scene, load_mesh(resolved).fitted(1.0))
        gpu.set_nodes(nodes)
        self.mesh_path = resolved
        self.apply_rotation()

    def open_file(self, path: str | os.PathLike) -> None:
        """Load a dropped or chosen file: an environment (.exr, .hdr) or a mesh.

        Raises
        ------
        InputFileError
            If the suffix is neither, or the file cannot be read.
        """
        suffix = Path(path).suffix.lower()
        if suffix in HDR_SUFFIXES:
            self.load_environment(path)
        elif suffix in MESH_SUFFIXES:
            self.load_mesh(path)
        else:
            raise InputFileError(
                f"{path}: not an environment ({', '.join(HDR_SUFFIXES)}) "
                f"or a mesh ({', '.join(MESH_SUFFIXES)})"
            )

    def set_rotation(self, rotation: Angles | list[float]) -> None:
        """Set the object rotation (XYZ degrees, wrapped to [-180, 180)) and apply it."""
        self.rotation = [_wrap_degrees(float(a)) for a in rotation]
        self.apply_rotation()

    def advance(self, seconds: float) -> None:
        """Turn the object by the turntable speed over ``seconds`` (if the turntable is on)."""
        if self.turntable and self.turntable_speed:
            x, y, z = self.rotation
            self.set_rotation((x, y + self.turntable_speed * seconds, z))

    def apply_rotation(self) -> None:
        """Write the object rotation into the reflectors' transforms and refresh the GPU copies."""
        gpu = self.session.gpu_scene
        for node in gpu.scene.reflectors():
            base = self._base_rotation.get(id(node), (0.0, 0.0, 0.0))
            node.transform.rotation = tuple(b + r for b, r in zip(base, self.rotation, strict=True))
        gpu.refresh_transforms()

    def _remember_scene_reflectors(self, reflectors: list[Node]) -> None:
        """Keep the scene file's reflectors and their own rotations."""
        self._scene_reflectors = list(reflectors)
        self._base_rotation = {id(node): tuple(node.transform.rotation) for node in reflectors}
