"""The common scene: environment, camera and a flat list of object nodes (plain data).

Every method renders the same :class:`Scene`. Nodes have a role:
``reflector`` objects are drawn by the selected method; ``local`` objects are
ordinary diffuse geometry near the reflector (a room, coloured boxes) that the
frame draws directly and that some methods render into cube maps or trace.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import numpy.typing as npt

from envstudio.core.transforms import Mat4, rotation_xyz, scaling, translation
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.environment import Environment
from envstudio.scene.material import Material
from envstudio.scene.mesh import MeshData
from envstudio.scene.proxy import Proxy

Role = Literal["reflector", "local"]


@dataclass
class Transform:
    """Translation, XYZ Euler rotation (degrees) and uniform scale."""

    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    scale: float = 1.0

    def matrix(self) -> Mat4:
        """Model matrix T · R · S."""
        return translation(self.translation) @ rotation_xyz(self.rotation) @ scaling(self.scale)


@dataclass
class Node:
    """One object: a mesh with a material, placed by a transform."""

    name: str
    mesh: MeshData
    material: Material = field(default_factory=Material)
    transform: Transform = field(default_factory=Transform)
    role: Role = "reflector"
    color: tuple[float, float, float] = (0.8, 0.8, 0.8)


@dataclass
class Scene:
    """Environment at infinity, objects, and the default camera."""

    environment: Environment
    nodes: list[Node]
    camera: OrbitCamera = field(default_factory=OrbitCamera)
    name: str = "scene"
    #: What replaced the scene file's own environment or reflector ("" when nothing did).
    variant: str = ""
    #: The proxy volume of a parallax-corrected cube map (scene/proxy.py), None when the
    #: scene declares none.
    proxy: Proxy | None = None
    #: The scene file it was read from ("" for a scene built otherwise): what a bake of
    #: the scene loads again (``pem``'s full orbit).
    source: str = ""

    @property
    def label(self) -> str:
        """The scene as a report names it: its name, and what replaced parts of it."""
        return f"{self.name} with {self.variant}" if self.variant else self.name

    def reflectors(self) -> list[Node]:
        """Nodes drawn by the selected method."""
        return [n for n in self.nodes if n.role == "reflector"]

    def local_objects(self) -> list[Node]:
        """Diffuse geometry near the reflectors."""
        return [n for n in self.nodes if n.role == "local"]

    def reflector_centre(self) -> npt.NDArray[np.float64]:
        """(3,) world-space centre of the reflectors' bounding box (cube-map origin)."""
        corners = []
        for node in self.reflectors():
            lo, hi = node.mesh.bounds()
            box = np.array(
                [
                    [x, y, z, 1.0]
                    for x in (lo[0], hi[0])
                    for y in (lo[1], hi[1])
                    for z in (lo[2], hi[2])
                ]
            )
            corners.append((node.transform.matrix() @ box.T).T[:, :3])
        if not corners:
            return np.zeros(3)
        pts = np.concatenate(corners)
        return (pts.min(axis=0) + pts.max(axis=0)) / 2
