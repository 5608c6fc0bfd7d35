"""What a method receives each frame: the scene on the GPU and the view.

:class:`GpuScene` owns the GPU copies of the common scene (environment cube map
with a full mip chain, SH coefficients, meshes) shared by all methods, so
switching methods costs nothing. :class:`FrameInputs` is one frame's camera,
viewport and timer.

Every environment-map method reads :meth:`GpuScene.static_environment`, not the
raw environment: the scene as seen from the reflectors' centre, the local
objects drawn over the far field. This is the "static EM" of seed 003 (section 1,
Figure 1c: EMs "are constructed from a single point like the reflective object's
center", without the reflector itself, so self-reflections and parallax are
lost). It is
captured by the one-pass cube capture of kautz's dynamic mode
(envmap.dynamic_cube) once per change of the environment, of a local object
(mesh, transform, albedo) or of the reflectors' centre, never per frame. Without
local objects it is the environment cube map itself.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.sh import project_latlong_sh9
from envstudio.core.transforms import Mat4, normal_matrix
from envstudio.envmap.conversions import latlong_to_cube, upload_latlong
from envstudio.envmap.dynamic_cube import DynamicCube, LocalObject
from envstudio.gpu.mesh import GpuMesh
from envstudio.gpu.programs import ProgramLibrary
from envstudio.gpu.timers import PassTimer
from envstudio.gpu.uniforms import set_uniform
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene


@dataclass
class GpuNode:
    """A scene node with its GPU mesh and matrices."""

    node: Node
    mesh: GpuMesh
    model: Mat4
    normal: npt.NDArray[np.float32]


@dataclass(frozen=True)
class StaticEnvironment:
    """The environment an environment-map method reads (seed 003 Figure 1c's static EM).

    Attributes
    ----------
    cube : moderngl.TextureCube
        RGBA32F cube map with its full (hardware box-filtered) mip chain, level 0
        ``GpuScene.cube_size`` texels: the local objects over the far field seen
        from the reflectors' centre, or ``GpuScene.cube`` itself without local objects.
    revision : int
        Changes whenever the content of ``cube`` may have changed; key what is
        derived from it (SH, filtered chains) on ``(id(scene), revision)``.
    captured : bool
        True when local objects were drawn into ``cube``: what is derived from the
        environment must then come from ``cube``, not from the lat-long map.
    """

    cube: moderngl.TextureCube
    revision: int
    captured: bool


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
        self._uploads = 0  # set_nodes calls: new meshes, even where an id is reused
        self._capture: DynamicCube | None = None
        self._static_inputs: tuple | None = None
        self._static_revision = 0
        self._centre_key: tuple | None = None
        self._centre = np.zeros(3)
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
        self._uploads += 1

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

    def local_capture_objects(self) -> list[LocalObject]:
        """The local objects as the cube capture draws them: mesh, model, normal matrix, albedo."""
        return [(g.mesh, g.model, g.normal, g.node.color) for g in self.local_objects()]

    def reflector_centre(self) -> npt.NDArray[np.float64]:
        """(3,) float, centre of the reflectors' bounding box: where cube maps are captured.

        Recomputed only when a reflector's mesh or model matrix changed.
        """
        key = tuple((id(g.node), id(g.node.mesh), g.model.tobytes()) for g in self.reflectors())
        if key != self._centre_key:
            self._centre = self.scene.reflector_centre()
            self._centre_key = key
        return self._centre

    def static_environment(self, timer: PassTimer | None = None) -> StaticEnvironment:
        """The environment as seen from the reflectors' centre (module docstring, seed 003).

        Parameters
        ----------
        timer
            Where a capture is reported (pass ``environment.capture``), if one is needed.

        Returns
        -------
        StaticEnvironment
            ``cube`` is valid until the next scene change; do not release it.
        """
        inputs = self._static_key()
        if inputs != self._static_inputs:
            self._static_revision += 1
            self._static_inputs = inputs
            if self.local_objects():
                self._capture_static(timer)
            else:
                self._release_capture()
        if self._capture is None:
            return StaticEnvironment(self.cube, self._static_revision, captured=False)
        return StaticEnvironment(self._capture.cube, self._static_revision, captured=True)

    def _static_key(self) -> tuple:
        """What the static environment depends on: the environment, local objects, centre."""
        local = tuple(
            (g.model.tobytes(), tuple(float(c) for c in g.node.color)) for g in self.local_objects()
        )
        if not local:
            return (self.environment_revision,)
        centre = self.reflector_centre().tobytes()
        return (self.environment_revision, self._uploads, local, centre)

    def _capture_static(self, timer: PassTimer | None) -> None:
        """Render the local objects over the environment from the centre, then the mips."""
        if self._capture is None or self._capture.size != self.cube_size:
            self._release_capture()
            self._capture = DynamicCube(self.ctx, self.programs, self.cube_size)
        with timer.measure("environment.capture") if timer else contextlib.nullcontext():
            self._capture.capture(
                self.cube, self.sh9, self.local_capture_objects(), self.reflector_centre()
            )
            self._capture.build_mipmaps(cross_face=False)

    @property
    def cube_levels(self) -> int:
        """Number of mip levels of the environment cube map."""
        return int(np.log2(self.cube_size)) + 1

    def _release_environment(self) -> None:
        for tex in (self.latlong, self.cube):
            if tex is not None:
                tex.release()
        self.latlong = self.cube = None

    def _release_capture(self) -> None:
        if self._capture is not None:
            self._capture.release()
        self._capture = None

    def _release_nodes(self) -> None:
        for gpu_node in self.nodes:
            gpu_node.mesh.release()
        self.nodes = []

    def release(self) -> None:
        """Free every GPU resource; safe to call twice."""
        self._release_environment()
        self._release_nodes()
        self._release_capture()
        self._static_inputs = None


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

    def draw_reflectors(self, program: moderngl.Program) -> None:
        """Draw every reflector with ``program``: ``u_view`` and ``u_projection`` of this
        frame, ``u_model`` and ``u_normal_matrix`` per node (common/mesh_vs.glsl's inputs)."""
        set_uniform(program, "u_view", self.view)
        set_uniform(program, "u_projection", self.projection)
        for gpu_node in self.scene.reflectors():
            set_uniform(program, "u_model", gpu_node.model)
            set_uniform(program, "u_normal_matrix", gpu_node.normal)
            gpu_node.mesh.render(program)
