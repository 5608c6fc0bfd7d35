"""Split screen and error heat map: method A against method B (usually the reference).

Both methods render into their own HDR targets through :class:`FrameRenderer`
(sharing the display settings); shaders/frame/split.glsl composes them: A left
of a draggable divider and B right, or, with the heat map on, the relative
luminance error |A − B| / B on A's side with its colour scale
(core/colormap.py). Pixels outside the reflectors match in both renders and
show zero error.
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl

from envstudio.engine.display import TONEMAPS
from envstudio.engine.frame import FrameRenderer
from envstudio.engine.frame_stats import FrameStats
from envstudio.engine.method import Method
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.gpu.programs import ProgramLibrary
from envstudio.gpu.uniforms import set_uniform
from envstudio.scene.camera import OrbitCamera
from envstudio.shading.gpu_scene import GpuScene


@dataclass
class SplitSettings:
    """What the compare view shows.

    Attributes
    ----------
    split : bool
        Show B right of the divider.
    divider : float
        Divider position as a fraction of the width (0–1).
    heat : bool
        Show A's relative error against B as a heat map.
    heat_scale : float
        Relative error at the top of the colour scale.
    """

    split: bool = True
    divider: float = 0.5
    heat: bool = False
    heat_scale: float = 0.25


class SplitView:
    """Renders two methods and composes them.

    Parameters
    ----------
    renderer
        The renderer of method A; its display settings are shared with B's.
    """

    def __init__(self, renderer: FrameRenderer):
        self.ctx = renderer.ctx
        self.programs: ProgramLibrary = renderer.programs
        self.renderer_a = renderer
        self.renderer_b = FrameRenderer(self.ctx, self.programs)
        self.renderer_b.display = renderer.display
        self._fullscreen = FullscreenPass(self.ctx)

    def render(
        self,
        scene: GpuScene,
        method_a: Method,
        method_b: Method,
        camera: OrbitCamera,
        size: tuple[int, int],
        target: moderngl.Framebuffer,
        settings: SplitSettings,
        viewport: tuple[int, int, int, int] | None = None,
    ) -> tuple[FrameStats, FrameStats]:
        """Render A and B at ``size`` and compose them into ``viewport`` (x, y, w, h) of
        ``target`` (default: (0, 0, *size))."""
        stats = []
        for renderer, method in ((self.renderer_a, method_a), (self.renderer_b, method_b)):
            renderer.timer.begin_frame()
            renderer.render_hdr(scene, method, camera, size)
            stats.append(FrameStats(dict(renderer.timer.times_ms), renderer.timer.clock))
        target.use()
        viewport = viewport or (0, 0, *size)
        self.ctx.viewport = viewport
        self.ctx.disable(moderngl.DEPTH_TEST | moderngl.BLEND)
        program = self.programs.get("frame/split.glsl")
        self.renderer_a.hdr_texture.use(location=0)
        self.renderer_b.hdr_texture.use(location=1)
        display = self.renderer_a.display
        set_uniform(program, "u_hdr_a", 0)
        set_uniform(program, "u_hdr_b", 1)
        set_uniform(program, "u_exposure", float(display["exposure"]))
        set_uniform(program, "u_tonemap", TONEMAPS.index(display["tonemap"]))
        # gl_FragCoord counts from the target's corner, not the viewport's
        set_uniform(program, "u_divider", float(viewport[0] + settings.divider * viewport[2]))
        set_uniform(program, "u_split", settings.split)
        set_uniform(program, "u_heat", settings.heat)
        set_uniform(program, "u_heat_scale", float(settings.heat_scale))
        self._fullscreen.draw(program)
        return stats[0], stats[1]

    def release(self) -> None:
        """Free B's renderer and the full-screen vertex arrays; safe to call twice."""
        self.renderer_b.release()
        self._fullscreen.release()
