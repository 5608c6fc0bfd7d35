"""A rendering session: context, program cache, GPU scene, frame renderer and methods.

The window and the headless commands both drive a :class:`RenderSession`;
the window passes its own context and framebuffer, headless use makes an EGL
context and renders into an offscreen 8-bit target.
"""

from __future__ import annotations

import sys

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.parameters import parse_assignments
from envstudio.engine.display import DISPLAY_NAMES
from envstudio.engine.frame import FrameRenderer
from envstudio.engine.frame_stats import FrameStats
from envstudio.engine.method import Method
from envstudio.engine.registry import available_methods, method_class
from envstudio.errors import ParameterError
from envstudio.gpu.context import create_headless_context
from envstudio.gpu.programs import ProgramLibrary
from envstudio.scene.graph import Scene
from envstudio.shading.gpu_scene import GpuScene


def material_values(scene: Scene) -> dict[str, float | str]:
    """Method parameter values implied by the first reflector's material."""
    reflectors = scene.reflectors()
    if not reflectors:
        return {}
    material = reflectors[0].material
    model = {} if material.model is None else {"model": material.model}
    return model | {
        "kd": tuple(material.kd),
        "fresnel": material.fresnel,
        "phong_exponent": material.phong_exponent,
        "sharpness": material.sharpness,
        "tangent_field": material.tangent_field.kind,
        "tangent_axis": material.tangent_field.axis,
    }


class RenderSession:
    """Everything needed to render a scene with any registered method.

    Parameters
    ----------
    scene
        The scene to show.
    ctx
        An existing context (the window's); None makes a headless EGL context.
    cube_size
        Environment cube map size.
    """

    def __init__(self, scene: Scene, ctx: moderngl.Context | None = None, cube_size: int = 256):
        self._owns_ctx = ctx is None
        self.ctx = ctx or create_headless_context()
        self.programs = ProgramLibrary(self.ctx)
        self.gpu_scene = GpuScene(self.ctx, self.programs, scene, cube_size)
        self.renderer = FrameRenderer(self.ctx, self.programs)
        self.camera = scene.camera
        self._methods: dict[str, Method] = {}
        self._ldr: moderngl.Framebuffer | None = None

    @property
    def scene(self) -> Scene:
        """The scene being shown."""
        return self.gpu_scene.scene

    def method(self, name: str) -> Method:
        """The instance of method ``name`` (created on first use with the scene's material)."""
        if name not in self._methods:
            method = method_class(name)(self.ctx, self.programs)
            method.values.update(material_values(self.scene), ignore_unknown=True)
            self._methods[name] = method
        return self._methods[name]

    def reset_values(self) -> None:
        """Every method made so far and the display back to the values a fresh session gives
        them: the parameters' defaults, the scene's material over them."""
        material = material_values(self.scene)
        for method in self._methods.values():
            method.values.update({p.name: p.default for p in method.parameters})
            method.values.update(material, ignore_unknown=True)
        self.renderer.display.update({p.name: p.default for p in self.renderer.display})

    def apply(self, method: Method, assignments: list[str]) -> None:
        """Apply ``name=value`` strings to the method's or the display's parameters.

        Raises
        ------
        ParameterError
            A name neither the method nor the display declares, or a bad value.
        """
        for name, value in parse_assignments(assignments).items():
            if name in method.values:
                method.values[name] = value
            elif name in DISPLAY_NAMES:
                self.renderer.display[name] = value
            else:
                own = ", ".join(p.name for p in method.values) or "none"
                raise ParameterError(
                    f"unknown parameter {name!r} for method {method.name} "
                    f"(method: {own}; display: {', '.join(DISPLAY_NAMES)})"
                )

    def method_names(self) -> list[str]:
        """Registered method names."""
        return list(available_methods())

    def render_offscreen(self, method: str | Method, size: tuple[int, int]) -> FrameStats:
        """Render one frame into the offscreen 8-bit target of ``size``."""
        method = self.method(method) if isinstance(method, str) else method
        target = self._ldr_target(size)
        return self.renderer.render(self.gpu_scene, method, self.camera, size, target)

    def read_ldr(self) -> npt.NDArray[np.uint8]:
        """(h, w, 3) uint8 of the last offscreen frame as displayed, row 0 at the top."""
        w, h = self._ldr.size
        data = np.frombuffer(self._ldr.read(components=3), dtype=np.uint8)
        return np.ascontiguousarray(data.reshape(h, w, 3)[::-1])

    def read_hdr(self) -> npt.NDArray[np.float32]:
        """(h, w, 3) float32 linear radiance of the last frame, row 0 at the top."""
        return self.renderer.read_hdr()

    def _ldr_target(self, size: tuple[int, int]) -> moderngl.Framebuffer:
        if self._ldr is None or self._ldr.size != tuple(size):
            if self._ldr is not None:
                for attachment in self._ldr.color_attachments:
                    attachment.release()
                self._ldr.release()
            self._ldr = self.ctx.framebuffer([self.ctx.texture(size, 4)])
        return self._ldr

    def release(self) -> None:
        """Free every GPU resource (and the context if this session made it); safe twice."""
        for method in self._methods.values():
            method.release()
        self._methods.clear()
        if self._ldr is not None:
            for attachment in self._ldr.color_attachments:
                attachment.release()
            self._ldr.release()
            self._ldr = None
        self.renderer.release()
        self.gpu_scene.release()
        self.programs.release()
        if self._owns_ctx and self.ctx is not None:
            self.ctx.release()
            self.ctx = None


def render_until_finished(session, method, size: tuple[int, int]):
    """Render frames until the method is finished (one for one-shot methods), with progress
    on stderr when it is a terminal; the last frame's stats."""
    from tqdm import tqdm

    stats = session.render_offscreen(method, size)
    if method.finished():
        return stats
    with tqdm(
        desc=method.name,
        unit="frame",
        file=sys.stderr,
        disable=not sys.stderr.isatty(),
        bar_format="{desc}: {n} frames {elapsed} {postfix}",
    ) as bar:
        while not method.finished():
            stats = session.render_offscreen(method, size)
            bar.update(1)
            bar.set_postfix_str(method.status_line())
    if method.status_line():
        print(f"{method.name}: {method.status_line()}", file=sys.stderr)
    return stats
