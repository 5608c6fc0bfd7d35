"""What a method receives each frame: the scene on the GPU and the view.

:class:`GpuScene` owns the GPU copies of the common scene (environment cube map
with a full mip chain, SH coefficients, meshes) shared by all methods, so
switching methods costs nothing. :class:`FrameInputs` is one frame's camera,
viewport and timer.
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.sh import project_latlong_sh9
from envstudio.core.transforms import Mat4, normal_matrix
from envstudio.envmap.conversions import latlong_to_cube, upload_latlong
from envstudio.gpu.mesh import GpuMesh
from envstudio.gpu.programs import ProgramLibrary
from envstudio.gpu.timers import PassTimer
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene


@dataclass
class GpuNode:
    """A scene node with its GPU mesh and matrices."""

    node: Node
    mesh: GpuMesh
    model: Mat4
    normal: npt.NDArray[np.float32]


class GpuScene:
    """GPU resources of a :class:`Scene`, shared by every method.

    Parameters
    ----------
    ctx, programs
        Context and its program cache.
    scene
        The scene to upload.
    cube_size
        Edge length in texels of the environment cube map's level 0.
    """

    def __init__(
        self, ctx: moderngl.Context, programs: ProgramLibrary, scene: Scene, cube_size: int = 256
    ):
        self.ctx = ctx
        self.programs = programs
        self.scene = scene
        self.cube_size = cube_size
        self.environment_revision = 0
        self.geometry_revision = 0
        self.latlong: moderngl.Texture | None = None
        self.cube: moderngl.TextureCube | None = None
        self.sh9 = np.zeros((9, 3), dtype=np.float32)
        self.nodes: list[GpuNode] = []
        self.set_environment(scene.environment)
        self.set_nodes(scene.nodes)

    def set_environment(self, environment: Environment) -> None:
        """Upload a new environment: lat-long texture, cube map with mips, SH9."""
        latlong = upload_latlong(self.ctx, environment.radiance)
        cube = latlong_to_cube(self.ctx, self.programs, latlong, self.cube_size)
        self._release_environment()
        self.latlong, self.cube = latlong, cube
        self.sh9 = project_latlong_sh9(environment.radiance).astype(np.float32)
        self.scene.environment = environment
        self.environment_revision += 1

    def set_nodes(self, nodes: list[Node]) -> None:
        """Upload the meshes of ``nodes`` (replacing the previous ones)."""
        uploaded = [
            GpuNode(
                n,
                GpuMesh(self.ctx, n.mesh),
                n.transform.matrix(),
                normal_matrix(n.transform.matrix()),
            )
            for n in nodes
        ]
        self._release_nodes()
        self.nodes = uploaded
        self.scene.nodes = list(nodes)
        self.geometry_revision += 1

    def refresh_transforms(self) -> None:
        """Recompute model matrices after a node's transform changed."""
        for gpu_node in self.nodes:
            gpu_node.model = gpu_node.node.transform.matrix()
            gpu_node.normal = normal_matrix(gpu_node.model)
        self.geometry_revision += 1

    def reflectors(self) -> list[GpuNode]:
        """GPU nodes drawn by the method."""
        return [g for g in self.nodes if g.node.role == "reflector"]

    def local_objects(self) -> list[GpuNode]:
        """GPU nodes drawn by the frame as diffuse geometry."""
        return [g for g in self.nodes if g.node.role == "local"]

    @property
    def cube_levels(self) -> int:
        """Number of mip levels of the environment cube map."""
        return int(np.log2(self.cube_size)) + 1

    def _release_environment(self) -> None:
        for tex in (self.latlong, self.cube):
            if tex is not None:
                tex.release()
        self.latlong = self.cube = None

    def _release_nodes(self) -> None:
        for gpu_node in self.nodes:
            gpu_node.mesh.release()
        self.nodes = []

    def release(self) -> None:
        """Free every GPU resource; safe to call twice."""
        self._release_environment()
        self._release_nodes()


@dataclass
class FrameInputs:
    """One frame as a method sees it.

    Attributes
    ----------
    scene : GpuScene
        Shared GPU scene.
    view, projection : (4, 4) float32
        Camera matrices (world → view, view → clip).
    camera_position : (3,) float
        Eye position in world space.
    size : tuple of int
        Viewport width and height in pixels.
    timer : PassTimer
        Where the method reports each pass.
    target : moderngl.Framebuffer
        The HDR framebuffer to draw into (bound when ``render`` is called);
        methods that render elsewhere (cube faces, prefilter passes) rebind it
        with ``target.use()`` before drawing the reflectors.
    """

    scene: GpuScene
    view: Mat4
    projection: Mat4
    camera_position: npt.NDArray[np.float64]
    size: tuple[int, int]
    timer: PassTimer
    target: moderngl.Framebuffer
