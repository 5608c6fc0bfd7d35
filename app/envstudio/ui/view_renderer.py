"""The 3D view of one frame: the method on show, split against another, or the grid of
methods, rendered into the view's GL viewport of the window."""

from __future__ import annotations

import sys

from moderngl_window.context.base import BaseWindow

from envstudio.engine.grid_view import GridView, tile_layout
from envstudio.engine.session import RenderSession
from envstudio.engine.split_view import SplitView
from envstudio.errors import UserError
from envstudio.gpu.programs import ShaderCompileError
from envstudio.measure.matching import GlossinessLink
from envstudio.ui.compare_panel import CompareState
from envstudio.ui.docking import pixel_scale
from envstudio.ui.grid import GridMetrics, GridState, draw_labels
from envstudio.ui.method_choice import MethodChoice
from envstudio.ui.stats import FrameHistory
from envstudio.ui.status import StatusLine


class ViewRenderer:
    """Renders the view each frame; a method's error is shown and the viewer keeps running.

    Parameters
    ----------
    wnd
        The window (its screen framebuffer, its point and pixel sizes).
    session
        The scene on the GPU, its camera and renderer.
    choice
        The method on show and access to the others.
    compare
        The split screen's other method and glossiness matching.
    grid
        The grid view's state.
    history
        Receives each frame's pass times (the Stats panel).
    status
        Where errors are shown.
    """

    def __init__(
        self,
        wnd: BaseWindow,
        session: RenderSession,
        choice: MethodChoice,
        compare: CompareState,
        grid: GridState,
        history: FrameHistory,
        status: StatusLine,
    ):
        self.wnd = wnd
        self.session = session
        self.choice = choice
        self.compare = compare
        self.grid = grid
        self.history = history
        self.status = status
        self.split_view = SplitView(session.renderer)
        self.grid_view = GridView(session.renderer)
        self.grid_metrics = GridMetrics(session.renderer, choice.truth)
        self.grid_labels: list[tuple[float, float, float, float]] = []
        """The grid's tile labels drawn last frame (x, y, w, h in window points)."""
        # glossiness matching through the ground truth's N, as compare matches
        self.grid_link, self.split_link = GlossinessLink(), GlossinessLink()
        self._error: str | None = None

    def render(self, viewport: tuple[int, int, int, int], frametime: float) -> None:
        """The grid when it is on, else the method on show (or the split), into ``viewport``."""
        if self.grid.on:
            self._render_grid(viewport, frametime)
        else:
            self._render_view(viewport, frametime)

    def _render_view(self, viewport: tuple[int, int, int, int], frametime: float) -> None:
        """The scene by the method on show (or split against another) at the viewport's size;
        the frame's times go to the Stats history."""
        size = viewport[2:]
        screen = self.wnd.ctx.screen
        session, compare, choice = self.session, self.compare, self.choice
        try:
            if compare.other:
                if compare.match:
                    self.split_link.follow(
                        [choice.method(compare.other)],
                        choice.method(choice.name),
                        choice.hub(),
                        session.gpu_scene.cube_size,
                    )
                    compare.match_note = self.split_link.lines.get(compare.other)
                else:
                    self.split_link.forget()
                stats, _ = self.split_view.render(
                    session.gpu_scene,
                    choice.method(choice.name),
                    choice.method(compare.other),
                    session.camera,
                    size,
                    screen,
                    compare.settings,
                    viewport,
                )
            else:
                stats = session.renderer.render(
                    session.gpu_scene,
                    choice.method(choice.name),
                    session.camera,
                    size,
                    screen,
                    viewport,
                )
        except (UserError, ShaderCompileError) as exc:
            # a bad value, or a shader this driver cannot compile (e.g. the reference
            # needs GLSL 4.30): say so and keep the viewer running
            self._report_error(f"{choice.name}: {str(exc).splitlines()[0]}")
        else:
            self._error = None
            self.history.add(frametime * 1e3, stats)

    def _render_grid(self, viewport: tuple[int, int, int, int], frametime: float) -> None:
        """Every method picked, one tile each, into ``viewport`` under the shared camera,
        matched to the method on show when matching is on; then the tiles' labels."""
        grid, choice, session = self.grid, self.choice, self.session
        # the last frame's time without the reference numbers' step (not the tiles' cost)
        if grid.scale.observe(frametime * 1e3 - self.grid_metrics.spent_ms):
            grid.numbers.clear()
        names = grid.names(list(choice.available))
        grid.tiles = tile_layout(names, viewport, grid.scale.fraction)
        main = choice.method(choice.name)
        methods = {name: choice.method(name) for name in names}
        if self.compare.match:  # when one changes, the others follow (as compare matches)
            cube = session.gpu_scene.cube_size
            self.grid_link.follow(list(methods.values()), main, choice.hub(), cube)
        else:
            self.grid_link.forget()
        screen = self.wnd.ctx.screen
        stats, errors = self.grid_view.render(
            session.gpu_scene, methods, session.camera, grid.tiles, screen
        )
        grid.record_times({name: s.total_ms for name, s in stats.items()}, errors)
        if errors:  # each in its tile's label too
            self._report_error("; ".join(f"{n}: {e}" for n, e in errors.items()))
        else:
            self._error = None
        if stats:  # the Stats panel: the main method's passes (else the first tile's)
            shown = stats.get(choice.name) or next(iter(stats.values()))
            self.history.add(frametime * 1e3, shown)
        self.grid_metrics.update(grid, methods, session, choice.hub(), screen)
        scale = pixel_scale(self.wnd.size, self.wnd.buffer_size)
        self.grid_labels = draw_labels(grid, scale, self.wnd.buffer_size[1])

    def _report_error(self, message: str) -> None:
        """Show a method's one-line error (and print it once) instead of quitting."""
        if message != self._error:
            print(f"envstudio: error: {message}", file=sys.stderr)
            self.status.error(message)
            self._error = message

    def release(self) -> None:
        """Free the split screen's, the grid's and the grid metrics' GPU resources."""
        self.split_view.release()
        self.grid_view.release()
        self.grid_metrics.release()
