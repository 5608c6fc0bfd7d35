"""Feed moderngl-window input events to Dear ImGui through its event queue.

moderngl-window 3.1.1's bundled integration writes ``io.mouse_down[...]``
directly, so a press and a release that arrive between two frames cancel out
and the click is lost. ImGui's event queue (``io.add_mouse_button_event`` and
friends, ImGui ≥ 1.87) keeps both: with ``io.config_input_trickle_event_queue``
(the default) the press is applied in one frame and the release in the next,
so a fast click still activates a button.

Coordinates are window coordinates in points, origin top-left, exactly as
moderngl-window reports them; ImGui's display is the whole window
(``display_size = wnd.size``) and :class:`~envstudio.ui.imgui_renderer.ImGuiRenderer`
covers the whole framebuffer, so no viewport offset is applied.

Hook it into a ``WindowConfig``: forward every event unconditionally, and let
the camera act only when ImGui does not claim the device::

    def on_mouse_drag_event(self, x, y, dx, dy):
        self.gui_input.on_mouse_drag_event(x, y, dx, dy)
        if not self.gui_input.want_capture_mouse:
            self.camera.drag(dx, dy)
"""

from __future__ import annotations

from typing import Any

from imgui_bundle import imgui
from moderngl_window.context.base import BaseKeys, KeyModifiers
from moderngl_window.context.base.window import MouseButtons

# moderngl-window button numbers -> ImGui's (0 left, 1 right, 2 middle).
_MOUSE_BUTTONS = {MouseButtons.left: 0, MouseButtons.right: 1, MouseButtons.middle: 2}

# BaseKeys names whose ImGui key is not simply the lower-cased name.
_RENAMED = {"LEFT": "left_arrow", "RIGHT": "right_arrow", "UP": "up_arrow", "DOWN": "down_arrow"}

_UNDEFINED = "undefined"

# The smallest frame time given to ImGui, which rejects a zero delta after frame 0.
_MIN_DELTA_TIME = 1e-5


def _imgui_key(name: str) -> imgui.Key | None:
    """The ImGui key for a :class:`BaseKeys` constant name, or ``None`` if it has none."""
    if name in _RENAMED:
        attr = _RENAMED[name]
    elif name.startswith("NUMBER_"):
        attr = "_" + name.removeprefix("NUMBER_")
    elif name.startswith("NUMPAD_"):
        attr = "keypad" + name.removeprefix("NUMPAD_")
    else:
        attr = name.lower()
    return getattr(imgui.Key, attr, None)


def key_map(window_keys: type[BaseKeys]) -> dict[Any, imgui.Key]:
    """Map a window backend's key codes to ImGui keys.

    Parameters
    ----------
    window_keys
        The backend's :class:`BaseKeys` subclass, ``wnd.keys``.

    Returns
    -------
    dict
        Key code (as the backend passes it to ``on_key_event``) → ``imgui.Key``,
        for every key the backend defines and ImGui knows.
    """
    mapping = {}
    for name in dir(BaseKeys):
        if not name.isupper() or name.startswith("ACTION_"):
            continue
        code = getattr(window_keys, name)
        key = _imgui_key(name)
        if code != _UNDEFINED and key is not None:
            mapping[code] = key
    return mapping


class ImGuiInput:
    """Translates moderngl-window events into ImGui input events.

    Parameters
    ----------
    io
        ``imgui.get_io()`` of the context that receives the events.
    window_keys
        The window backend's key constants, ``wnd.keys``.
    """

    def __init__(self, io: imgui.IO, window_keys: type[BaseKeys]):
        self.io = io
        self._keys = window_keys
        self._key_map = key_map(window_keys)
        self._modifier_keys = {
            getattr(window_keys, name): mod
            for name, mod in (
                ("LEFT_CTRL", imgui.Key.mod_ctrl),
                ("LEFT_SHIFT", imgui.Key.mod_shift),
                ("RIGHT_SHIFT", imgui.Key.mod_shift),
            )
            if getattr(window_keys, name) != _UNDEFINED
        }

    @property
    def want_capture_mouse(self) -> bool:
        """ImGui uses the mouse (hovering or dragging a panel): keep the camera still."""
        return self.io.want_capture_mouse

    @property
    def want_capture_keyboard(self) -> bool:
        """ImGui uses the keyboard (a text field is active): ignore shortcuts."""
        return self.io.want_capture_keyboard

    def prepare_frame(
        self, window_size: tuple[int, int], buffer_size: tuple[int, int], delta_time: float
    ) -> None:
        """Set display size, framebuffer scale and frame time; call before ``imgui.new_frame()``.

        Parameters
        ----------
        window_size
            ``wnd.size``: the window in points (the unit of mouse coordinates).
        buffer_size
            ``wnd.buffer_size``: the framebuffer in pixels (larger on HiDPI screens).
        delta_time
            Seconds since the previous frame (``frametime``); clamped above zero.
        """
        width, height = window_size
        self.io.display_size = (float(width), float(height))
        if width > 0 and height > 0:
            self.io.display_framebuffer_scale = (buffer_size[0] / width, buffer_size[1] / height)
        self.io.delta_time = max(float(delta_time), _MIN_DELTA_TIME)

    def on_key_event(self, key: Any, action: Any, modifiers: KeyModifiers) -> None:
        """Forward a key press or release with the modifier state; repeats are ignored.

        Some platforms (GLFW on X11) report modifiers as they were *before* the
        event, so pressing Ctrl alone arrives with ``modifiers.ctrl`` false; the
        modifier keys moderngl-window names (left Ctrl, both Shifts) therefore
        set their modifier from the action itself.
        """
        if action == self._keys.ACTION_PRESS:
            down = True
        elif action == self._keys.ACTION_RELEASE:
            down = False
        else:
            return
        mods = {
            imgui.Key.mod_ctrl: bool(modifiers.ctrl),
            imgui.Key.mod_shift: bool(modifiers.shift),
            imgui.Key.mod_alt: bool(modifiers.alt),
        }
        if key in self._modifier_keys:
            mods[self._modifier_keys[key]] = down
        for mod, held in mods.items():
            self.io.add_key_event(mod, held)
        imgui_key = self._key_map.get(key)
        if imgui_key is not None:
            self.io.add_key_event(imgui_key, down)

    def on_mouse_position_event(self, x: float, y: float, dx: float, dy: float) -> None:
        """Forward a cursor move (no button held)."""
        self.io.add_mouse_pos_event(float(x), float(y))

    def on_mouse_drag_event(self, x: float, y: float, dx: float, dy: float) -> None:
        """Forward a cursor move with a button held."""
        self.io.add_mouse_pos_event(float(x), float(y))

    def on_mouse_press_event(self, x: float, y: float, button: int) -> None:
        """Forward a button press at ``(x, y)``."""
        self._button(x, y, button, down=True)

    def on_mouse_release_event(self, x: float, y: float, button: int) -> None:
        """Forward a button release at ``(x, y)``."""
        self._button(x, y, button, down=False)

    def on_mouse_scroll_event(self, x_offset: float, y_offset: float) -> None:
        """Forward wheel motion; positive ``y_offset`` scrolls up, as in GLFW and ImGui."""
        self.io.add_mouse_wheel_event(float(x_offset), float(y_offset))

    def on_unicode_char_entered(self, char: str) -> None:
        """Forward typed text (one or more characters)."""
        for c in char:
            self.io.add_input_character(ord(c))

    def _button(self, x: float, y: float, button: int, down: bool) -> None:
        index = _MOUSE_BUTTONS.get(button)
        if index is None:
            return
        self.io.add_mouse_pos_event(float(x), float(y))
        self.io.add_mouse_button_event(index, down)
