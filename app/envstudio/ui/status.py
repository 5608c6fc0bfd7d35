"""The status line along the bottom of the 3D view: busy work, errors and notes.

Errors are one-line :class:`~envstudio.errors.UserError` messages (several on
separate lines) shown in red until dismissed or replaced; a note (a saved
capture) stays grey until the next one; the busy line names work queued for
the next frame.
"""

from __future__ import annotations

from imgui_bundle import imgui

from envstudio.ui.docking import ViewRect

ERROR_COLOUR = (1.0, 0.35, 0.3, 1.0)
BUSY_COLOUR = (1.0, 0.8, 0.3, 1.0)
NOTE_COLOUR = (0.75, 0.75, 0.75, 1.0)
_MARGIN = 8.0

_FLAGS = (
    imgui.WindowFlags_.no_decoration
    | imgui.WindowFlags_.no_move
    | imgui.WindowFlags_.no_saved_settings
    | imgui.WindowFlags_.no_focus_on_appearing
    | imgui.WindowFlags_.no_nav
    | imgui.WindowFlags_.always_auto_resize
)


class StatusLine:
    """Messages for the user, drawn as a small window at the bottom-left."""

    def __init__(self):
        self.error_text: str | None = None
        self.note_text: str | None = None
        self.busy_text: str | None = None
        self.mode_text: str | None = None
        """What the view is doing, in grey until replaced (the grid's tile size)."""

    def error(self, message: str) -> None:
        """Show ``message`` in red (one line per problem; long lines wrap)."""
        self.error_text = message

    def note(self, message: str) -> None:
        """Show ``message`` in grey."""
        self.note_text = message

    def draw(self, area: ViewRect | None = None) -> None:
        """Draw the line, if there is anything to say, at the bottom-left of ``area`` (the
        3D view; default the whole display), between ``new_frame`` and ``render``."""
        if not (self.error_text or self.note_text or self.busy_text or self.mode_text):
            return
        if area is None:
            display = imgui.get_io().display_size
            area = ViewRect(0.0, 0.0, display.x, display.y)
        corner = (area.x + _MARGIN, area.y + area.height - _MARGIN)
        imgui.set_next_window_pos(corner, imgui.Cond_.always, (0.0, 1.0))
        imgui.set_next_window_size_constraints(
            (0.0, 0.0), (max(area.width - 2 * _MARGIN, 1.0), max(area.height / 2, 1.0))
        )
        imgui.set_next_window_bg_alpha(0.85)
        imgui.begin("##status", None, _FLAGS)
        imgui.push_text_wrap_pos(area.width - 4 * _MARGIN)  # window-local
        if self.busy_text:
            imgui.text_colored(BUSY_COLOUR, f"busy: {self.busy_text}")
        if self.error_text:
            imgui.text_colored(ERROR_COLOUR, self.error_text)
            imgui.same_line()
            if imgui.small_button("dismiss"):
                self.error_text = None
        if self.note_text:
            imgui.text_colored(NOTE_COLOUR, self.note_text)
        if self.mode_text:
            imgui.text_colored(NOTE_COLOUR, self.mode_text)
        imgui.pop_text_wrap_pos()
        imgui.end()
