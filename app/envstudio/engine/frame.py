"""One frame, the same code path for the window, headless render, split screen and bench.

Passes, in order, into a float HDR target (linear radiance)::

    background  environment cube map along each view ray (optional)
    local       diffuse local objects lit by the environment's SH9 irradiance
    <method>    the selected method draws the reflectors (its own named passes)
    display     exposure, tone map, sRGB into the caller's framebuffer

The HDR target is kept for EXR capture (linear, before tone mapping) and for
comparisons against the reference.
"""

from __future__ import annotations

from typing import Protocol

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.parameters import ParameterValues
from envstudio.engine.display import TONEMAPS, display_values
from envstudio.engine.frame_stats import FrameStats
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.gpu.programs import ProgramLibrary
from envstudio.gpu.timers import PassTimer
from envstudio.gpu.uniforms import set_uniform
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.tangents import TangentField
from envstudio.shading.gpu_scene import FrameInputs, GpuScene
from envstudio.shading.tangent_buffers import TangentBuffers


class ReflectorPass(Protocol):
    """What a frame asks of the method drawing its reflectors.

    :class:`~envstudio.engine.method.Method` is the one implementation; naming it here
    would make the method contract (whose session protocol names this renderer) and
    the frame import each other.
    """

    def steer_camera(self, camera: OrbitCamera) -> None:
        """Move the camera before the frame."""

    def render(self, frame: FrameInputs) -> None:
        """Draw every reflector of ``frame.scene`` into the bound framebuffer."""


class FrameRenderer:
    """Renders a :class:`GpuScene` with a method into any framebuffer.

    Parameters
    ----------
    ctx
        The context.
    programs
        Its program cache (shared with the methods).
    """

    def __init__(self, ctx: moderngl.Context, programs: ProgramLibrary):
        self.ctx = ctx
        self.programs = programs
        self.display = display_values()
        self.timer = PassTimer(ctx)
        self._fullscreen = FullscreenPass(ctx)
        self._hdr: moderngl.Texture | None = None
        self._depth: moderngl.Renderbuffer | None = None
        self._fbo: moderngl.Framebuffer | None = None
        self._tangents: TangentBuffers | None = None

    @property
    def hdr_texture(self) -> moderngl.Texture | None:
        """The float colour target of the last frame (RGBA32F, linear radiance)."""
        return self._hdr

    @property
    def hdr_framebuffer(self) -> moderngl.Framebuffer | None:
        """The float target of the last frame (None before the first)."""
        return self._fbo

    def render_hdr(
        self, scene: GpuScene, method: ReflectorPass, camera: OrbitCamera, size: tuple[int, int]
    ) -> None:
        """Render background, local objects and the method's reflectors into the HDR target."""
        method.steer_camera(camera)
        self._ensure_target(size)
        fbo = self._fbo
        fbo.use()
        fbo.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)
        aspect = size[0] / size[1]
        view = camera.view_matrix()
        projection = camera.projection_matrix(aspect)
        self.ctx.enable(moderngl.DEPTH_TEST)
        self.ctx.disable(moderngl.BLEND | moderngl.CULL_FACE)
        if self.display["background"]:
            with self.timer.measure("background"):
                self._draw_background(scene, view, projection)
        with self.timer.measure("local"):
            self._draw_local(scene, view, projection)
        frame = FrameInputs(scene, view, projection, camera.position, size, self.timer, fbo)
        method.render(frame)
        fbo.use()

    def render(
        self,
        scene: GpuScene,
        method: ReflectorPass,
        camera: OrbitCamera,
        size: tuple[int, int],
        target: moderngl.Framebuffer,
        viewport: tuple[int, int, int, int] | None = None,
    ) -> FrameStats:
        """Render one frame and show it in ``target`` (the window or an offscreen LDR target).

        Parameters
        ----------
        size
            Render resolution (width, height) in pixels.
        target
            Framebuffer receiving the tone-mapped image.
        viewport
            Region of ``target`` (x, y, w, h); defaults to (0, 0, *size).
        """
        self.timer.begin_frame()
        self.render_hdr(scene, method, camera, size)
        with self.timer.measure("display"):
            self.present(target, viewport or (0, 0, *size))
        return FrameStats(dict(self.timer.times_ms), self.timer.clock)

    def present(
        self,
        target: moderngl.Framebuffer,
        viewport: tuple[int, int, int, int],
        display: ParameterValues | None = None,
    ) -> None:
        """Tone-map the HDR target into ``viewport`` of ``target``."""
        display = display or self.display
        target.use()
        self.ctx.viewport = viewport
        self.ctx.disable(moderngl.DEPTH_TEST | moderngl.BLEND)
        program = self.programs.get("frame/display.glsl")
        self._hdr.use(location=0)
        set_uniform(program, "u_hdr", 0)
        set_uniform(program, "u_exposure", float(display["exposure"]))
        set_uniform(program, "u_tonemap", TONEMAPS.index(display["tonemap"]))
        self._fullscreen.draw(program)

    def read_hdr(self) -> npt.NDArray[np.float32]:
        """(h, w, 3) float32 linear radiance of the last frame, row 0 at the top."""
        data = np.frombuffer(self._hdr.read(), dtype=np.float32)
        h, w = self._hdr.height, self._hdr.width
        return np.ascontiguousarray(data.reshape(h, w, 4)[::-1, :, :3])

    def reflector_coverage(
        self, scene: GpuScene, camera: OrbitCamera, size: tuple[int, int]
    ) -> npt.NDArray[np.bool_]:
        """(h, w) bool, row 0 at the top: the pixels whose nearest surface is a reflector.

        What the reference's footprint average keeps (its samples that miss the
        reflectors are dropped); ``compare`` box-filters a supersampled method over it.
        Uses the HDR target of ``size`` (its content is replaced).
        """
        program = self.programs.get("frame/coverage.glsl")
        self._draw_reflectors_over_locals(program, scene, camera, size)
        return self.read_hdr()[..., 0] > 0.5

    def reflector_surface(
        self, scene: GpuScene, camera: OrbitCamera, size: tuple[int, int]
    ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """The reflectors' shading frame at every pixel centre, row 0 at the top.

        Returns
        -------
        normals : (h, w, 3) float32
            The unit shading normal turned to the side of the face the camera sees (the
            reference's two-sided rule); zero where no reflector is the nearest surface.
        views : (h, w, 3) float32
            The unit direction from the surface point to the camera; zero likewise.

        Uses the HDR target of ``size`` (its content is replaced).
        """
        program = self.programs.get("frame/surface.glsl")
        set_uniform(program, "u_camera_position", camera.position.astype(np.float32))
        frames = []
        for output in (0, 1):
            set_uniform(program, "u_output", output)
            self._draw_reflectors_over_locals(program, scene, camera, size)
            frames.append(self.read_hdr())
        return frames[0], frames[1]

    def reflector_tangents(
        self, scene: GpuScene, camera: OrbitCamera, size: tuple[int, int], field: TangentField
    ) -> npt.NDArray[np.float32]:
        """The Banks material's unit tangent at every pixel centre, row 0 at the top: the
        tangent ``field`` (scene/tangents.py) made orthogonal to :meth:`reflector_surface`'s
        normal as the reference takes it (banks_brdf.glsl); (h, w, 3) float32, zero where no
        reflector is the nearest surface. Uses the HDR target of ``size``."""
        program = self.programs.get("frame/surface.glsl", {"TANGENTS": 1})
        set_uniform(program, "u_camera_position", camera.position.astype(np.float32))
        set_uniform(program, "u_output", 2)
        if self._tangents is None:
            self._tangents = TangentBuffers(self.ctx)
        self._draw_reflectors_over_locals(
            program,
            scene,
            camera,
            size,
            lambda gpu_node: self._tangents.render(program, gpu_node, field),
        )
        return self.read_hdr()

    def _draw_reflectors_over_locals(
        self, program: moderngl.Program, scene: GpuScene, camera: OrbitCamera, size, draw=None
    ) -> None:
        """Clear the HDR target of ``size`` and draw the local objects (``u_value`` 0: they
        hide what they cover) and then the reflectors (``u_value`` 1) with ``program``
        (``draw(gpu_node)`` draws a reflector, when given)."""
        self._ensure_target(size)
        self._fbo.use()
        self._fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        view, projection = camera.view_matrix(), camera.projection_matrix(size[0] / size[1])
        set_uniform(program, "u_view", view)
        set_uniform(program, "u_projection", projection)
        self.ctx.enable(moderngl.DEPTH_TEST)
        self.ctx.disable(moderngl.BLEND | moderngl.CULL_FACE)
        for value, nodes in ((0.0, scene.local_objects()), (1.0, scene.reflectors())):
            set_uniform(program, "u_value", value)
            for gpu_node in nodes:
                set_uniform(program, "u_model", gpu_node.model)
                set_uniform(program, "u_normal_matrix", gpu_node.normal)
                if draw is not None and value:
                    draw(gpu_node)
                else:
                    gpu_node.mesh.render(program)

    def _draw_background(self, scene: GpuScene, view, projection) -> None:
        program = self.programs.get("frame/background.glsl")
        rotation_only = view.copy()
        rotation_only[:3, 3] = 0.0
        inverse = np.linalg.inv(projection.astype(np.float64) @ rotation_only)
        scene.cube.use(location=0)
        set_uniform(program, "u_environment", 0)
        set_uniform(program, "u_inverse_view_projection", inverse.astype(np.float32))
        self.ctx.disable(moderngl.DEPTH_TEST)  # no depth writes: objects draw over it
        self._fullscreen.draw(program)
        self.ctx.enable(moderngl.DEPTH_TEST)

    def _draw_local(self, scene: GpuScene, view, projection) -> None:
        program = self.programs.get("frame/local_diffuse.glsl")
        set_uniform(program, "u_sh9", scene.sh9)
        set_uniform(program, "u_view", view)
        set_uniform(program, "u_projection", projection)
        for gpu_node in scene.local_objects():
            set_uniform(program, "u_model", gpu_node.model)
            set_uniform(program, "u_normal_matrix", gpu_node.normal)
            set_uniform(program, "u_albedo", tuple(float(c) for c in gpu_node.node.color))
            gpu_node.mesh.render(program)

    def _ensure_target(self, size: tuple[int, int]) -> None:
        if self._hdr is not None and self._hdr.size == tuple(size):
            return
        self._release_target()
        self._hdr = self.ctx.texture(size, 4, dtype="f4")
        self._hdr.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self._depth = self.ctx.depth_renderbuffer(size)
        self._fbo = self.ctx.framebuffer([self._hdr], self._depth)

    def _release_target(self) -> None:
        for obj in (self._fbo, self._hdr, self._depth):
            if obj is not None:
                obj.release()
        self._fbo = self._hdr = self._depth = None

    def release(self) -> None:
        """Free the targets, timer queries and full-screen vertex arrays; safe twice."""
        self._release_target()
        self.timer.release()
        self._fullscreen.release()
        if self._tangents is not None:
            self._tangents.release()
        self._tangents = None
