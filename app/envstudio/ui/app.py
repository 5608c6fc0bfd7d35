"""The desktop viewer: the scene rendered by the selected method, with ImGui panels docked
around it.

Each frame::

    run the jobs announced last frame (file loads)       DeferredWork.run_due
    poll "Open..." dialogs; the glossiness plot's points  ViewerPanels.step
      (measured by a child process: ui/error_plot.py)
    cycle methods; turntable
    imgui.new_frame → menu bar, dock space → the view's rectangle (ui/docking.py)
    panels, status line                                  ui/viewer_panels.py
    the view → the view's rectangle                      ui/view_renderer.py
                                                         capture without UI / EXR here
    imgui.render → ImGuiRenderer.render                  capture with UI here

The 3D view is the dock space's central node: it is rendered at that node's size
(so the camera's aspect ratio follows it) into that rectangle of the window;
with the panels hidden (Tab) it is the whole window.

Input goes to ImGui first; the camera and the shortcuts act only when ImGui
does not want the mouse / keyboard (ui/viewer_input.py). Shortcuts: 1–9 pick a
method, R resets the camera, Tab hides and shows the panels, F12 saves a PNG,
Escape quits.

Settings (method, parameter values per method, display, scene, environment,
mesh, camera, rotation, turntable, window size, panel layout, glossiness matching,
the grid: on, the methods picked, the tile fraction) are restored on
start and saved on exit (ui/viewer_state.py); command-line options win over them.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

import moderngl
from imgui_bundle import imgui, implot
from moderngl_window import WindowConfig
from moderngl_window.context.base import BaseWindow, KeyModifiers
from moderngl_window.timers.clock import Timer

from envstudio.engine.registry import method_class
from envstudio.engine.session import RenderSession
from envstudio.errors import ParameterError
from envstudio.io.atomic import check_output_path
from envstudio.io.scene_setup import DEFAULT_SCENE
from envstudio.ui.capture import read_framebuffer, save
from envstudio.ui.capture_control import CaptureControl
from envstudio.ui.compare_panel import CompareState
from envstudio.ui.docking import DockLayout, ViewRect, gl_viewport
from envstudio.ui.grid import GridState
from envstudio.ui.imgui_input import ImGuiInput
from envstudio.ui.imgui_renderer import ImGuiRenderer
from envstudio.ui.jobs import DeferredWork
from envstudio.ui.method_choice import MethodChoice
from envstudio.ui.scene_control import SceneControl
from envstudio.ui.settings import ViewerSettings, load_settings
from envstudio.ui.start_scene import StartScene, start_scene
from envstudio.ui.stats import FrameHistory
from envstudio.ui.status import StatusLine
from envstudio.ui.style import load_ui_font
from envstudio.ui.view_renderer import ViewRenderer
from envstudio.ui.viewer_input import ViewerInput
from envstudio.ui.viewer_panels import ViewerPanels
from envstudio.ui.viewer_state import restore_viewer_state, save_viewer_state
from envstudio.ui.window import open_window

TITLE = "envmap-studio"
CYCLE_FRAMES = 2
"""Frames each method is shown with ``--cycle-methods``."""
MIN_WINDOW_SIZE = (320, 240)
MAX_WINDOW_SIZE = (16384, 16384)


@dataclass
class RunOptions:
    """Command-line behaviour of one run (``--frames``, ``--screenshot``, ``--cycle-methods``,
    ``--compare``, ``--hide-panels``)."""

    frames: int = 0
    screenshot: Path | None = None
    cycle_methods: bool = False
    compare: str | None = None
    hide_panels: bool = False
    grid: list[str] | None = None


def run_viewer(args: argparse.Namespace) -> int:
    """Open the viewer window and run until it is closed (or ``--frames`` are drawn).

    Parameters
    ----------
    args
        The ``view`` options: scene, env, mesh, method, frames, screenshot, cycle_methods.

    Returns
    -------
    int
        Exit status 0.

    Raises
    ------
    UserError
        A bad option or file named on the command line, or no display.
    """
    if args.frames < 0:
        raise ParameterError(f"--frames {args.frames}: expected a count >= 0")
    screenshot = None
    if args.screenshot:
        screenshot = check_output_path(args.screenshot)
        if screenshot.suffix.lower() != ".png":
            raise ParameterError(f"--screenshot {screenshot}: expected a .png file name")
    if args.method:
        method_class(args.method)
    if args.compare:
        method_class(args.compare)
    grid = None
    if getattr(args, "grid", None) is not None:
        grid = [name for name in args.grid.split(",") if name] if args.grid != "all" else []
        for name in grid:
            method_class(name)
    settings, warning = load_settings()
    warnings = [warning] if warning else []
    start = start_scene(args, settings, warnings)
    for line in warnings:
        print(f"envstudio: warning: {line}", file=sys.stderr)
    window = open_window(_window_size(settings.window_size), TITLE)
    try:
        viewer = Viewer(
            ctx=window.ctx,
            wnd=window,
            timer=Timer(),
            start=start,
            settings=settings,
            method=args.method,
            options=RunOptions(
                args.frames,
                screenshot,
                args.cycle_methods,
                args.compare,
                args.hide_panels,
                grid,
            ),
            warnings=warnings,
        )
        try:
            viewer.run()
        finally:
            viewer.shutdown()
    finally:
        window.destroy()
    return 0


def _window_size(saved: list) -> tuple[int, int]:
    """The saved window size within sane limits (the default if malformed)."""
    if len(saved) != 2 or not all(isinstance(v, int) and not isinstance(v, bool) for v in saved):
        saved = ViewerSettings().window_size
    return tuple(
        min(max(v, lo), hi)
        for v, lo, hi in zip(saved, MIN_WINDOW_SIZE, MAX_WINDOW_SIZE, strict=True)
    )


class Viewer(WindowConfig):
    """The viewer's window: it wires the parts together, draws each frame and forwards input.

    Parameters
    ----------
    ctx, wnd, timer
        The window's context, the window and its frame timer.
    start
        The scene to show first.
    settings
        Settings read at start; updated and saved when :meth:`run` ends.
    method
        Method named on the command line (None: the one last shown).
    options
        ``--frames``, ``--screenshot``, ``--cycle-methods``.
    warnings
        Messages to show in the status line from the start.
    """

    def __init__(
        self,
        ctx: moderngl.Context,
        wnd: BaseWindow,
        timer: Timer,
        start: StartScene,
        settings: ViewerSettings,
        method: str | None,
        options: RunOptions,
        warnings: list[str],
    ):
        super().__init__(ctx=ctx, wnd=wnd, timer=timer)
        wnd.exit_key = None  # Escape is a shortcut, ignored while ImGui has the keyboard
        self.settings = settings
        self.options = options
        # Tab shows and hides them; --hide-panels wins over the saved state
        self.panels_shown = settings.panels_shown and not options.hide_panels
        self.status = StatusLine()
        self.jobs = DeferredWork(self.status)
        self.session = session = RenderSession(start.scene, ctx=ctx)
        self.control = SceneControl(
            session, start.spec, start.reflectors, start.environment, start.mesh
        )
        self.compare = CompareState(other=options.compare)
        self.choice = MethodChoice(
            session, settings.method_values, method, settings.method, self.compare, self.status
        )
        self.grid = GridState()
        if options.grid is not None:  # the command line wins over the saved grid
            self.grid.picked = list(options.grid)
            self.grid.enter()
        self.history = FrameHistory()
        self.view_renderer = ViewRenderer(
            wnd, session, self.choice, self.compare, self.grid, self.history, self.status
        )
        self.captures = CaptureControl(
            ctx, session, self.control, self.choice, self.grid, self.status
        )
        self.panels = ViewerPanels(
            session,
            self.control,
            self.choice,
            self.compare,
            self.grid,
            self.history,
            self.captures,
            self.jobs,
            self.status,
        )
        self.frames_drawn = 0

        problems = restore_viewer_state(
            settings,
            session,
            self.control,
            self.compare,
            self.grid,
            list(self.choice.available),
            restore_grid=options.grid is None,
            restore_split=options.compare is None,  # the command line wins over the saved split
            same_scene=start.spec == (settings.scene or DEFAULT_SCENE),
        ) + self.choice.restore(self.choice.name)
        for problem in problems:
            print(f"envstudio: warning: {problem}", file=sys.stderr)
        if warnings or problems:
            self.status.error("\n".join([*warnings, *problems]))
        imgui.create_context()
        io = imgui.get_io()
        io.set_ini_filename(None)  # the layout is kept in the settings file
        io.config_flags |= imgui.ConfigFlags_.docking_enable
        load_ui_font()
        if settings.imgui_ini:
            imgui.load_ini_settings_from_memory(settings.imgui_ini)
        implot.create_context()
        self.gui_input = ImGuiInput(io, wnd.keys)
        self.gui = ImGuiRenderer(ctx)
        self.input = ViewerInput(
            wnd,
            self.gui_input,
            session,
            self.choice,
            self.compare,
            self.grid,
            self.captures,
            self.control,
            self.jobs,
            self.toggle_panels,
        )
        self.layout = DockLayout()
        self.view = ViewRect(0.0, 0.0, float(wnd.size[0]), float(wnd.size[1]))
        """The 3D view's rectangle in window points (the dock space's central node)."""
        self.gui_input.prepare_frame(wnd.size, wnd.buffer_size, 1.0 / 60.0)
        imgui.new_frame()
        self.layout.warm_up()
        imgui.end_frame()

    def toggle_panels(self) -> None:
        """Hide the panels, or show them again (a clean view, and clean screenshots)."""
        self.panels_shown = not self.panels_shown

    def run(self) -> None:
        """The main loop: draw and swap until the window is closing, then save the settings.

        Settings are saved only after a normal end, so a crash cannot persist
        the state that caused it.
        """
        self.timer.start()
        while not self.wnd.is_closing:
            now, delta = self.timer.next_frame()
            self.wnd.use()
            self.wnd.render(now, delta)
            if not self.wnd.is_closing:
                self.wnd.swap_buffers()
        self.timer.stop()
        save_viewer_state(
            self.settings,
            self.session,
            self.control,
            self.compare,
            self.grid,
            method=self.choice.name,
            used_methods=self.choice.used,
            window_size=self.wnd.size,
            imgui_ini=imgui.save_ini_settings_to_memory(),
            panels_shown=self.panels_shown,
        )

    def on_render(self, time: float, frametime: float) -> None:
        """Draw one frame: scene, panels, captures; stop after ``--frames``."""
        self.jobs.run_due()
        self.panels.poll_dialogs()
        self.panels.step()
        if self.options.cycle_methods and self.frames_drawn % CYCLE_FRAMES == 0:
            self.choice.cycle(first=self.frames_drawn == 0)
        self.control.advance(frametime)
        size = self.wnd.buffer_size
        if size[0] < 1 or size[1] < 1:
            return
        self.gui_input.prepare_frame(self.wnd.size, size, frametime)
        imgui.new_frame()
        self.view = self.layout.frame(self.panels_shown)
        viewport = gl_viewport(self.view, self.wnd.size, size)
        view_size = viewport[2:]
        if self.panels_shown:
            self.panels.draw(self.gui, view_size)
        if self.layout.toggle_panels:  # View > Hide panels; from the next frame
            self.panels_shown = False
        request = self.captures.take_pending()
        # the grid's capture is the view with its labels, read after the UI: no status line
        grid_capture = self.grid.on and request is not None and not request.with_ui
        self.status.mode_text = self.grid.scale.status() if self.grid.on else None
        if not grid_capture:
            self.status.draw(self.view)
        screen = self.ctx.screen
        if viewport != (0, 0, *size) or self.grid.on:  # the panels' background, the gaps
            screen.use()
            screen.clear(0.0, 0.0, 0.0, 1.0, viewport=(0, 0, *size))
        if view_size[0] >= 1 and view_size[1] >= 1:
            self.view_renderer.render(viewport, frametime)
            if not self.grid.on and request and not request.with_ui:
                self.captures.take(request, view_size, viewport[:2])

        imgui.render()
        self.wnd.use()
        self.gui.render(imgui.get_draw_data())
        self.jobs.mark_shown()
        if request and (request.with_ui or grid_capture):
            if grid_capture:
                self.captures.take(request, viewport[2:], viewport[:2])
            else:
                self.captures.take(request, size)

        self.frames_drawn += 1
        if self.options.frames and self.frames_drawn >= self.options.frames:
            if self.options.screenshot:
                save(self.options.screenshot, read_framebuffer(screen, size))
            self.wnd.close()

    def on_key_event(self, key, action, modifiers: KeyModifiers) -> None:
        """Keys go to ImGui, then to the shortcuts."""
        self.input.key(key, action, modifiers)

    def on_mouse_position_event(self, x: int, y: int, dx: int, dy: int) -> None:
        """Cursor moves (no button held) go to ImGui only."""
        self.input.mouse_position(x, y, dx, dy)

    def on_mouse_press_event(self, x: int, y: int, button: int) -> None:
        """A press starts a camera gesture unless it was over a panel."""
        self.input.mouse_press(x, y, button, self.view)

    def on_mouse_release_event(self, x: int, y: int, button: int) -> None:
        """A release ends the camera gesture."""
        self.input.mouse_release(x, y, button)

    def on_mouse_drag_event(self, x: int, y: int, dx: int, dy: int) -> None:
        """Drags orbit or pan the camera, or move the split screen's divider."""
        self.input.mouse_drag(x, y, dx, dy, self.view)

    def on_mouse_scroll_event(self, x_offset: float, y_offset: float) -> None:
        """The wheel zooms unless it is over a panel."""
        self.input.mouse_scroll(x_offset, y_offset)

    def on_unicode_char_entered(self, char: str) -> None:
        """Typed text goes to ImGui."""
        self.input.text(char)

    def on_files_dropped_event(self, x: int, y: int, paths: list[str]) -> None:
        """Dropped environments and meshes load as jobs."""
        self.input.files_dropped(paths)

    def shutdown(self) -> None:
        """Free the UI and GPU resources (before the window goes)."""
        self.panels.close()
        self.gui.release()
        self.view_renderer.release()
        implot.destroy_context()
        imgui.destroy_context()
        self.session.release()
