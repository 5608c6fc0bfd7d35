"""The desktop viewer: the scene rendered by the selected method, with ImGui panels docked
around it.

Each frame::

    run the jobs announced last frame (file loads)       DeferredWork.run_due
    poll "Open..." dialogs; cycle methods; turntable
    imgui.new_frame → menu bar, dock space → the view's rectangle (ui/docking.py)
    panels, status line
    FrameRenderer.render → the view's rectangle          capture without UI / EXR here
    imgui.render → ImGuiRenderer.render                  capture with UI here

The 3D view is the dock space's central node: it is rendered at that node's size
(so the camera's aspect ratio follows it) into that rectangle of the window;
with the panels hidden (Tab) it is the whole window.

Input goes to ImGui first; the camera and the shortcuts act only when ImGui
does not want the mouse / keyboard. Shortcuts: 1–9 pick a method, R resets the
camera, Tab hides and shows the panels, F12 saves a PNG, Escape quits.

Settings (method, parameter values per method, display, scene, environment,
mesh, camera, rotation, turntable, window size, panel layout, glossiness matching,
the grid: on, the methods picked, the tile fraction) are restored on
start and saved on exit; command-line options win over them.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import moderngl
import numpy as np
from imgui_bundle import imgui, implot
from moderngl_window import WindowConfig
from moderngl_window.context.base import BaseWindow, KeyModifiers
from moderngl_window.timers.clock import Timer

from envstudio.core.parameters import ParameterValues
from envstudio.engine.grid_view import GridView, tile_layout
from envstudio.engine.method import Method
from envstudio.engine.registry import available_methods, ground_truth_class, method_class
from envstudio.engine.session import RenderSession
from envstudio.engine.split_view import SplitView
from envstudio.errors import ParameterError, UserError
from envstudio.gpu.programs import ShaderCompileError
from envstudio.io.atomic import check_output_path
from envstudio.io.images import HDR_SUFFIXES
from envstudio.io.meshes import MESH_SUFFIXES, load_mesh
from envstudio.io.scene_file import shipped_scenes
from envstudio.io.scene_setup import DEFAULT_SCENE, build_scene, replace_reflector
from envstudio.measure.matching import GlossinessLink, match_through
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.graph import Node, Scene
from envstudio.ui.camera_control import CameraControl
from envstudio.ui.capture import (
    CaptureRequest,
    capture_path,
    default_captures_dir,
    read_framebuffer,
    save,
)
from envstudio.ui.compare_panel import CompareState, compare_panel
from envstudio.ui.docking import DockLayout, ViewRect, gl_viewport
from envstudio.ui.file_dialogs import OpenFileDialog
from envstudio.ui.grid import GridMetrics, GridState, draw_labels
from envstudio.ui.imgui_input import ImGuiInput
from envstudio.ui.imgui_renderer import ImGuiRenderer
from envstudio.ui.jobs import DeferredWork
from envstudio.ui.panels import (
    CaptureOptions,
    SceneDialogs,
    capture_panel,
    method_panel,
    scene_panel,
    stats_panel,
)
from envstudio.ui.scene_control import SceneControl
from envstudio.ui.settings import ViewerSettings, load_settings, save_settings
from envstudio.ui.stats import FrameHistory
from envstudio.ui.status import StatusLine
from envstudio.ui.style import load_ui_font
from envstudio.ui.window import open_window

TITLE = "envmap-studio"
CYCLE_FRAMES = 2
"""Frames each method is shown with ``--cycle-methods``."""
PROGRESSIVE_BUDGET_MS = 40.0
"""Milliseconds of progressive accumulation (the reference) per frame, so the UI stays live."""
MIN_WINDOW_SIZE = (320, 240)
MAX_WINDOW_SIZE = (16384, 16384)


@dataclass
class StartScene:
    """The scene the viewer opens with and where it came from.

    Attributes
    ----------
    scene : Scene
        Loaded scene (environment and reflector replacements applied).
    spec : str
        Shipped scene name or absolute scene file path.
    reflectors : list of Node
        The scene file's own reflectors.
    environment, mesh : str or None
        Replacement files.
    """

    scene: Scene
    spec: str
    reflectors: list[Node]
    environment: str | None
    mesh: str | None


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
    start = _start_scene(args, settings, warnings)
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


def _start_scene(
    args: argparse.Namespace, settings: ViewerSettings, warnings: list[str]
) -> StartScene:
    """The scene from the command line, else the one last shown (falling back to the default)."""
    given = (args.scene, args.env, args.mesh)
    if args.scene is None:
        wanted = (settings.scene, args.env or settings.environment, args.mesh or settings.mesh)
    else:
        wanted = given
    try:
        return _load_start(*wanted, args.max_env_width)
    except UserError as exc:
        if wanted == given:
            raise
        warnings.append(f"cannot restore the last scene ({exc}); using the defaults")
        return _load_start(*given, args.max_env_width)


def _load_start(
    spec: str | None, environment: str | None, mesh: str | None, max_env_width: int | None
) -> StartScene:
    spec = spec or DEFAULT_SCENE
    scene = build_scene(spec, environment, None, max_env_width)
    reflectors = scene.reflectors()
    if mesh:
        scene.nodes = replace_reflector(scene, load_mesh(mesh).fitted(1.0))
    if spec not in shipped_scenes():
        spec = str(Path(spec).resolve())
    return StartScene(scene, spec, reflectors, environment, mesh)


def _window_size(saved: list) -> tuple[int, int]:
    """The saved window size within sane limits (the default if malformed)."""
    if len(saved) != 2 or not all(isinstance(v, int) and not isinstance(v, bool) for v in saved):
        saved = ViewerSettings().window_size
    return tuple(
        min(max(v, lo), hi)
        for v, lo, hi in zip(saved, MIN_WINDOW_SIZE, MAX_WINDOW_SIZE, strict=True)
    )


def restore_values(values: ParameterValues, saved: object) -> list[str]:
    """Assign the saved ``{name: value}`` entries that are declared and valid.

    Returns
    -------
    list of str
        One message per rejected value (unknown names are skipped silently:
        a parameter may have been renamed since the settings were written).
    """
    if not isinstance(saved, dict):
        return [f"expected a table of parameter values, got {type(saved).__name__}"]
    problems = []
    for name, value in saved.items():
        if name in values:
            try:
                values[name] = value
            except ParameterError as exc:
                problems.append(str(exc))
    return problems


def restore_camera(camera: OrbitCamera, saved: dict) -> list[str]:
    """Set the saved azimuth, elevation, distance and target; returns rejected entries."""
    problems = []
    for key in ("azimuth", "elevation", "distance"):
        value = saved.get(key)
        if _is_number(value):
            setattr(camera, key, float(value))
        elif key in saved:
            problems.append(f"camera.{key} = {value!r}, expected a number")
    target = saved.get("target")
    if isinstance(target, list) and len(target) == 3 and all(_is_number(v) for v in target):
        camera.target = np.array(target, dtype=np.float64)
    elif "target" in saved:
        problems.append(f"camera.target = {target!r}, expected [x, y, z]")
    camera.orbit(0.0, 0.0)
    camera.zoom(1.0)
    return problems


def _ground_truth_name() -> str | None:
    try:
        return ground_truth_class().name
    except ParameterError:  # no plugin declares one: the grid shows no PSNR / FLIP
        return None


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


class Viewer(WindowConfig):
    """The viewer's window callbacks, frame and panels.

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
        self.session = RenderSession(start.scene, ctx=ctx)
        self.control = SceneControl(
            self.session, start.spec, start.reflectors, start.environment, start.mesh
        )
        self.methods = available_methods()
        self._restored_methods: set[str] = set()
        saved_method = settings.method if settings.method in self.methods else None
        self.method_name = method or saved_method or next(iter(self.methods))
        self.camera_control = CameraControl(wnd.mouse.left, wnd.mouse.right)
        self.compare = CompareState(other=options.compare)
        self.split_view = SplitView(self.session.renderer)
        self.grid = GridState()
        self.grid_view = GridView(self.session.renderer)
        self.grid_metrics = GridMetrics(self.session.renderer, _ground_truth_name())
        self.grid_labels: list[tuple[float, float, float, float]] = []
        # glossiness matching through the ground truth's N, as compare matches
        self.grid_link, self.split_link = GlossinessLink(), GlossinessLink()
        if options.grid is not None:  # the command line wins over the saved grid
            self.grid.picked = list(options.grid)
            self.grid.enter()
        self.history = FrameHistory()
        self.capture = CaptureOptions(str(default_captures_dir()))
        self._capture_request: CaptureRequest | None = None
        self._render_error: str | None = None
        self.dialogs = SceneDialogs(
            OpenFileDialog("Open environment", "HDR environments", HDR_SUFFIXES),
            OpenFileDialog("Open mesh", "Meshes", MESH_SUFFIXES),
        )
        self.frames_drawn = 0
        keys = wnd.keys
        self._number_keys = [getattr(keys, f"NUMBER_{i}") for i in range(1, 10)]

        problems = self._restore(settings, start) + self._restore_method(self.method_name)
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
        self.gui_input = ImGuiInput(io, keys)
        self.gui = ImGuiRenderer(ctx)
        self.layout = DockLayout()
        self.view = ViewRect(0.0, 0.0, float(wnd.size[0]), float(wnd.size[1]))
        """The 3D view's rectangle in window points (the dock space's central node)."""
        self.gui_input.prepare_frame(wnd.size, wnd.buffer_size, 1.0 / 60.0)
        imgui.new_frame()
        self.layout.warm_up()
        imgui.end_frame()

    def _restore(self, settings: ViewerSettings, start: StartScene) -> list[str]:
        """Apply the saved display, camera, rotation and turntable; returns what was rejected."""
        problems = restore_values(self.session.renderer.display, settings.display)
        self.compare.match = settings.match_glossiness
        if self.options.grid is None:
            problems += self.grid.restore(settings.grid, list(self.methods))
        if self.options.compare is None:  # the command line wins over the saved split
            problems += self.compare.restore(settings.compare, list(self.methods))
        if start.spec == (settings.scene or DEFAULT_SCENE):
            problems += restore_camera(self.session.camera, settings.camera)
        rotation = settings.object_rotation
        if len(rotation) == 3 and all(_is_number(v) for v in rotation):
            self.control.set_rotation(rotation)
        else:
            problems.append(f"object_rotation = {rotation!r}, expected [x, y, z] degrees")
        self.control.turntable = settings.turntable
        if _is_number(settings.turntable_speed):
            self.control.turntable_speed = float(settings.turntable_speed)
        else:
            problems.append(f"turntable_speed = {settings.turntable_speed!r}, expected deg/s")
        return [f"settings: {problem}" for problem in problems]

    def method(self, name: str) -> Method:
        """The session's method ``name``: saved parameter values on first use, the frame budget."""
        if name not in self._restored_methods:
            problems = self._restore_method(name)
            for problem in problems:
                print(f"envstudio: warning: {problem}", file=sys.stderr)
            if problems:
                self.status.error("\n".join(problems))
        method = self.session.method(name)
        # progressive methods work within the budget, whichever way they were first reached
        method.frame_budget_ms = PROGRESSIVE_BUDGET_MS
        return method

    def _restore_method(self, name: str) -> list[str]:
        """Give method ``name`` its saved parameter values; returns what was rejected."""
        self._restored_methods.add(name)
        saved = self.settings.method_values.get(name, {})
        problems = restore_values(self.session.method(name).values, saved)
        return [f"settings: {name}: {problem}" for problem in problems]

    def select_method(self, name: str) -> None:
        """Show method ``name`` (with the look of the previous one when matching is on)."""
        previous = self.method(self.method_name)
        chosen = self.method(name)
        try:
            chosen.prepare(self.session.gpu_scene)
        except UserError as exc:  # e.g. a bake for another scene: keep the method on show
            self.status.error(f"{name}: {exc}")
            return
        if self.compare.match and chosen is not previous:
            lines = match_through([chosen], previous, self._hub(), self.session.gpu_scene.cube_size)
            self.compare.match_note = lines.get(name)
        self.method_name = name

    def _cycle(self) -> None:
        """``--cycle-methods``: the next method (the first shown at frame 0), printed on stdout."""
        names = list(self.methods)
        if self.frames_drawn > 0:
            following = names[(names.index(self.method_name) + 1) % len(names)]
            if following == self.method_name:
                return
            self.select_method(following)
        print(f"envstudio: method {self.method_name}", flush=True)

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
        self._save_settings()

    def on_render(self, time: float, frametime: float) -> None:
        """Draw one frame: scene, panels, captures; stop after ``--frames``."""
        self.jobs.run_due()
        self._poll_dialogs()
        if self.options.cycle_methods and self.frames_drawn % CYCLE_FRAMES == 0:
            self._cycle()
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
            self._panels(view_size)
        if self.layout.toggle_panels:  # View > Hide panels; from the next frame
            self.panels_shown = False
        request, self._capture_request = self._capture_request, None
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
            if self.grid.on:
                self._render_grid(viewport, frametime)
            else:
                self._render_view(view_size, viewport, frametime)
                if request and not request.with_ui:
                    self._take_capture(request, view_size, viewport[:2])

        imgui.render()
        self.wnd.use()
        self.gui.render(imgui.get_draw_data())
        self.jobs.mark_shown()
        if request and (request.with_ui or grid_capture):
            if grid_capture:
                self._take_capture(request, viewport[2:], viewport[:2])
            else:
                self._take_capture(request, size)

        self.frames_drawn += 1
        if self.options.frames and self.frames_drawn >= self.options.frames:
            if self.options.screenshot:
                save(self.options.screenshot, read_framebuffer(screen, size))
            self.wnd.close()

    def _render_view(
        self, size: tuple[int, int], viewport: tuple[int, int, int, int], frametime: float
    ) -> None:
        """The scene by the method on show (or split against another) at ``size``, into
        ``viewport`` of the window; the frame's times go to the Stats history."""
        screen = self.ctx.screen
        try:
            if self.compare.other:
                if self.compare.match:
                    self.split_link.follow(
                        [self.method(self.compare.other)],
                        self.method(self.method_name),
                        self._hub(),
                        self.session.gpu_scene.cube_size,
                    )
                    self.compare.match_note = self.split_link.lines.get(self.compare.other)
                else:
                    self.split_link.forget()
                stats, _ = self.split_view.render(
                    self.session.gpu_scene,
                    self.method(self.method_name),
                    self.method(self.compare.other),
                    self.session.camera,
                    size,
                    screen,
                    self.compare.settings,
                    viewport,
                )
            else:
                stats = self.session.renderer.render(
                    self.session.gpu_scene,
                    self.method(self.method_name),
                    self.session.camera,
                    size,
                    screen,
                    viewport,
                )
        except (UserError, ShaderCompileError) as exc:
            # a bad value, or a shader this driver cannot compile (e.g. the reference
            # needs GLSL 4.30): say so and keep the viewer running
            self._report_render_error(f"{self.method_name}: {str(exc).splitlines()[0]}")
        else:
            self._render_error = None
            self.history.add(frametime * 1e3, stats)

    def _render_grid(self, viewport: tuple[int, int, int, int], frametime: float) -> None:
        """Every method picked, one tile each, into ``viewport`` under the shared camera,
        matched to the method on show when matching is on; then the tiles' labels."""
        grid = self.grid
        # the last frame's time without the reference numbers' step (not the tiles' cost)
        if grid.scale.observe(frametime * 1e3 - self.grid_metrics.spent_ms):
            grid.numbers.clear()
        names = grid.names(list(self.methods))
        grid.tiles = tile_layout(names, viewport, grid.scale.fraction)
        main = self.method(self.method_name)
        methods = {name: self.method(name) for name in names}
        if self.compare.match:  # when one changes, the others follow (as compare matches)
            cube = self.session.gpu_scene.cube_size
            self.grid_link.follow(list(methods.values()), main, self._hub(), cube)
        else:
            self.grid_link.forget()
        stats, errors = self.grid_view.render(
            self.session.gpu_scene, methods, self.session.camera, grid.tiles, self.ctx.screen
        )
        grid.record_times({name: s.total_ms for name, s in stats.items()}, errors)
        if errors:  # each in its tile's label too
            self._report_render_error("; ".join(f"{n}: {e}" for n, e in errors.items()))
        else:
            self._render_error = None
        if stats:  # the Stats panel: the main method's passes (else the first tile's)
            shown = stats.get(self.method_name) or next(iter(stats.values()))
            self.history.add(frametime * 1e3, shown)
        self.grid_metrics.update(grid, methods, self.session, self._hub(), self.ctx.screen)
        scale, buffer_height = self._pixel_scale(), self.wnd.buffer_size[1]
        self.grid_labels = draw_labels(grid, scale, buffer_height)

    def _hub(self) -> Method | None:
        """The ground truth, whose Phong exponent every match goes through (None: none)."""
        truth = self.grid_metrics.truth
        return self.method(truth) if truth else None

    def _pixel_scale(self) -> tuple[float, float]:
        """Framebuffer pixels per window point (x, y)."""
        (w, h), (bw, bh) = self.wnd.size, self.wnd.buffer_size
        return (bw / w if w else 1.0, bh / h if h else 1.0)

    def _report_render_error(self, message: str) -> None:
        """Show a method's one-line error (and print it once) instead of quitting."""
        if message != self._render_error:
            print(f"envstudio: error: {message}", file=sys.stderr)
            self.status.error(message)
            self._render_error = message

    def _panels(self, size: tuple[int, int]) -> None:
        method = self.method(self.method_name)
        picked = method_panel(
            self.methods,
            method,
            self.session.scene,
            self.status,
            self.gui,
            self.session.renderer.display,
        )
        if picked:
            self.select_method(picked)
        scene_panel(
            self.control, self.session.renderer.display, self.dialogs, self.jobs, self.status
        )
        stats_panel(self.history, size)
        compare_panel(self.methods, self.method_name, self.compare, self.grid)
        if capture_panel(self.capture):
            self._request_capture(self.capture.fmt)

    def _poll_dialogs(self) -> None:
        environment = self.dialogs.environment.poll()
        if environment:
            self.jobs.submit(
                f"loading {environment.name}", lambda: self.control.load_environment(environment)
            )
        mesh = self.dialogs.mesh.poll()
        if mesh:
            self.jobs.submit(f"loading {mesh.name}", lambda: self.control.load_mesh(mesh))

    def _request_capture(self, fmt: str) -> None:
        """Take a capture of ``fmt`` during the next frame."""
        if self.grid.on and fmt != "png":
            self.status.error(f"grid view: {fmt} capture is of one method; click its tile first")
            return
        label = "grid" if self.grid.on else self.method_name
        try:
            path = capture_path(self.capture.folder, self.control.scene_label, label, fmt)
        except UserError as exc:
            self.status.error(str(exc))
            return
        self._capture_request = CaptureRequest(path, self.capture.with_ui and fmt == "png")

    def _take_capture(
        self, request: CaptureRequest, size: tuple[int, int], origin: tuple[int, int] = (0, 0)
    ) -> None:
        """Save ``request``: the HDR frame, or the ``size`` pixels of the window at ``origin``
        (the view alone, or the whole window with the UI)."""
        try:
            if request.is_hdr:
                pixels = self.session.read_hdr()
            else:
                pixels = read_framebuffer(self.ctx.screen, size, origin)
            path = save(request.path, pixels)
        except UserError as exc:
            self.status.error(str(exc))
            return
        self.status.note(f"saved {path}")

    def on_key_event(self, key, action, modifiers: KeyModifiers) -> None:
        """Keys go to ImGui; shortcuts act when ImGui does not want the keyboard."""
        self.gui_input.on_key_event(key, action, modifiers)
        keys = self.wnd.keys
        if action != keys.ACTION_PRESS or self.gui_input.want_capture_keyboard:
            return
        if key in self._number_keys:
            names = list(self.methods)
            index = self._number_keys.index(key)
            if index < len(names):
                self.select_method(names[index])
        elif key == keys.R:
            self.session.camera.reset()
        elif key == keys.TAB:  # a clean view, and clean screenshots
            self.panels_shown = not self.panels_shown
        elif key == keys.F12:
            self._request_capture("png")
        elif key == keys.ESCAPE:
            self.wnd.close()

    def on_mouse_position_event(self, x: int, y: int, dx: int, dy: int) -> None:
        """Cursor moves (no button held) go to ImGui only."""
        self.gui_input.on_mouse_position_event(x, y, dx, dy)

    def on_mouse_press_event(self, x: int, y: int, button: int) -> None:
        """A press starts a camera gesture unless it was over a panel."""
        self.gui_input.on_mouse_press_event(x, y, button)
        over_panel = self.gui_input.want_capture_mouse
        view = self.view
        if self.grid.on and not over_panel:
            self.grid.press = (x, y)
        on_divider = not over_panel and self.compare.grab(x - view.x, view.width)
        self.camera_control.press(button, self.wnd.modifiers.shift, over_panel or on_divider)

    def on_mouse_release_event(self, x: int, y: int, button: int) -> None:
        """A release ends the camera gesture."""
        self.gui_input.on_mouse_release_event(x, y, button)
        self.camera_control.release()
        self.compare.dragging = False
        press, self.grid.press = self.grid.press, None
        if self.grid.on and press is not None and button == self.wnd.mouse.left:
            clicked = self.grid.click(press, (x, y), self._pixel_scale(), self.wnd.buffer_size[1])
            if clicked:  # that method alone, as the main view
                self.select_method(clicked)
                self.grid.leave()

    def on_mouse_drag_event(self, x: int, y: int, dx: int, dy: int) -> None:
        """Drags orbit or pan the camera (if the gesture started outside the panels)."""
        self.gui_input.on_mouse_drag_event(x, y, dx, dy)
        self.compare.drag(x - self.view.x, self.view.width)
        self.camera_control.drag(self.session.camera, dx, dy, self.view.height)

    def on_mouse_scroll_event(self, x_offset: float, y_offset: float) -> None:
        """The wheel zooms unless it is over a panel."""
        self.gui_input.on_mouse_scroll_event(x_offset, y_offset)
        if not self.gui_input.want_capture_mouse:
            CameraControl.scroll(self.session.camera, y_offset)

    def on_unicode_char_entered(self, char: str) -> None:
        """Typed text goes to ImGui."""
        self.gui_input.on_unicode_char_entered(char)

    def on_files_dropped_event(self, x: int, y: int, paths: list[str]) -> None:
        """Load dropped environments (.exr, .hdr) and meshes, one job each."""
        for path in paths:
            self.jobs.submit(
                f"loading {Path(path).name}", lambda path=path: self.control.open_file(path)
            )

    def shutdown(self) -> None:
        """Free the UI and GPU resources (before the window goes)."""
        self.dialogs.environment.close()
        self.dialogs.mesh.close()
        self.gui.release()
        self.split_view.release()
        self.grid_view.release()
        self.grid_metrics.release()
        implot.destroy_context()
        imgui.destroy_context()
        self.session.release()

    def _save_settings(self) -> None:
        settings = self.settings
        settings.method = self.method_name
        for name in self._restored_methods:
            settings.method_values[name] = self.session.method(name).values.as_dict()
        settings.display = self.session.renderer.display.as_dict()
        settings.scene = self.control.scene_spec
        env, mesh = self.control.environment_path, self.control.mesh_path
        settings.environment = str(env) if env else None
        settings.mesh = str(mesh) if mesh else None
        camera = self.session.camera
        settings.camera = {
            "azimuth": camera.azimuth,
            "elevation": camera.elevation,
            "distance": camera.distance,
            "target": [float(v) for v in camera.target],
        }
        settings.object_rotation = list(self.control.rotation)
        settings.turntable = self.control.turntable
        settings.turntable_speed = self.control.turntable_speed
        settings.window_size = list(self.wnd.size)
        settings.imgui_ini = imgui.save_ini_settings_to_memory()
        settings.match_glossiness = self.compare.match
        settings.grid = self.grid.as_settings()
        settings.compare = self.compare.as_settings()
        settings.panels_shown = self.panels_shown
        try:
            save_settings(settings)
        except (OSError, UserError) as exc:
            print(f"envstudio: warning: settings not saved ({exc})", file=sys.stderr)
