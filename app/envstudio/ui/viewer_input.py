"""The viewer's keyboard and mouse: ImGui first, then the shortcuts and the view's gestures.

The camera, the split screen's divider, the grid's tiles and the shortcuts act only
when ImGui does not want the mouse / keyboard. Shortcuts: 1–9 pick a method, R
resets the camera, Tab hides and shows the panels, F12 saves a PNG, Escape quits.
Dropped environments and meshes load as jobs.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from moderngl_window.context.base import BaseWindow, KeyModifiers

from envstudio.engine.session import RenderSession
from envstudio.ui.camera_control import CameraControl
from envstudio.ui.capture_control import CaptureControl
from envstudio.ui.compare_panel import CompareState
from envstudio.ui.docking import ViewRect, pixel_scale
from envstudio.ui.grid import GridState
from envstudio.ui.imgui_input import ImGuiInput
from envstudio.ui.jobs import DeferredWork
from envstudio.ui.method_choice import MethodChoice
from envstudio.ui.scene_control import SceneControl


class ViewerInput:
    """Handles the window's input events after passing them to ImGui.

    Parameters
    ----------
    wnd
        The window (its key and button names, modifiers and sizes; Escape closes it).
    gui_input
        ImGui's input, which sees every event first.
    session
        Its camera is orbited, panned, zoomed and reset.
    choice
        The number keys and a click on a grid tile pick a method.
    compare
        The split screen's divider is dragged.
    grid
        A click on a tile leaves the grid for that method.
    captures
        F12 asks for a PNG.
    control, jobs
        Dropped files load through them.
    toggle_panels
        Tab hides or shows the panels.
    """

    def __init__(
        self,
        wnd: BaseWindow,
        gui_input: ImGuiInput,
        session: RenderSession,
        choice: MethodChoice,
        compare: CompareState,
        grid: GridState,
        captures: CaptureControl,
        control: SceneControl,
        jobs: DeferredWork,
        toggle_panels: Callable[[], None],
    ):
        self.wnd = wnd
        self.gui_input = gui_input
        self.session = session
        self.choice = choice
        self.compare = compare
        self.grid = grid
        self.captures = captures
        self.control = control
        self.jobs = jobs
        self.toggle_panels = toggle_panels
        self.camera_control = CameraControl(wnd.mouse.left, wnd.mouse.right)
        self._number_keys = [getattr(wnd.keys, f"NUMBER_{i}") for i in range(1, 10)]

    def key(self, key, action, modifiers: KeyModifiers) -> None:
        """Keys go to ImGui; shortcuts act when ImGui does not want the keyboard."""
        self.gui_input.on_key_event(key, action, modifiers)
        keys = self.wnd.keys
        if action != keys.ACTION_PRESS or self.gui_input.want_capture_keyboard:
            return
        if key in self._number_keys:
            names = list(self.choice.available)
            index = self._number_keys.index(key)
            if index < len(names):
                self.choice.select(names[index])
        elif key == keys.R:
            self.session.camera.reset()
        elif key == keys.TAB:  # a clean view, and clean screenshots
            self.toggle_panels()
        elif key == keys.F12:
            self.captures.request("png")
        elif key == keys.ESCAPE:
            self.wnd.close()

    def mouse_position(self, x: int, y: int, dx: int, dy: int) -> None:
        """Cursor moves (no button held) go to ImGui only."""
        self.gui_input.on_mouse_position_event(x, y, dx, dy)

    def mouse_press(self, x: int, y: int, button: int, view: ViewRect) -> None:
        """A press in ``view`` starts a camera gesture unless it was over a panel."""
        self.gui_input.on_mouse_press_event(x, y, button)
        over_panel = self.gui_input.want_capture_mouse
        if self.grid.on and not over_panel:
            self.grid.press = (x, y)
        on_divider = not over_panel and self.compare.grab(x - view.x, view.width)
        self.camera_control.press(button, self.wnd.modifiers.shift, over_panel or on_divider)

    def mouse_release(self, x: int, y: int, button: int) -> None:
        """A release ends the camera gesture; a click on a grid tile shows that method."""
        self.gui_input.on_mouse_release_event(x, y, button)
        self.camera_control.release()
        self.compare.dragging = False
        press, self.grid.press = self.grid.press, None
        if self.grid.on and press is not None and button == self.wnd.mouse.left:
            scale = pixel_scale(self.wnd.size, self.wnd.buffer_size)
            clicked = self.grid.click(press, (x, y), scale, self.wnd.buffer_size[1])
            if clicked:  # that method alone, as the main view
                self.choice.select(clicked)
                self.grid.leave()

    def mouse_drag(self, x: int, y: int, dx: int, dy: int, view: ViewRect) -> None:
        """Drags in ``view`` orbit or pan the camera (if the gesture started outside the
        panels) or move the split screen's divider."""
        self.gui_input.on_mouse_drag_event(x, y, dx, dy)
        self.compare.drag(x - view.x, view.width)
        self.camera_control.drag(self.session.camera, dx, dy, view.height)

    def mouse_scroll(self, x_offset: float, y_offset: float) -> None:
        """The wheel zooms unless it is over a panel."""
        self.gui_input.on_mouse_scroll_event(x_offset, y_offset)
        if not self.gui_input.want_capture_mouse:
            CameraControl.scroll(self.session.camera, y_offset)

    def text(self, char: str) -> None:
        """Typed text goes to ImGui."""
        self.gui_input.on_unicode_char_entered(char)

    def files_dropped(self, paths: list[str]) -> None:
        """Load dropped environments (.exr, .hdr) and meshes, one job each."""
        for path in paths:
            self.jobs.submit(
                f"loading {Path(path).name}", lambda path=path: self.control.open_file(path)
            )
