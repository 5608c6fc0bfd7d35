"""Captures asked for by the Capture panel or F12, taken during the next frame."""

from __future__ import annotations

import moderngl

from envstudio.engine.session import RenderSession
from envstudio.errors import UserError
from envstudio.ui.capture import (
    CaptureRequest,
    capture_path,
    default_captures_dir,
    read_framebuffer,
    save,
)
from envstudio.ui.grid import GridState
from envstudio.ui.method_choice import MethodChoice
from envstudio.ui.panels import CaptureOptions
from envstudio.ui.scene_control import SceneControl
from envstudio.ui.status import StatusLine


class CaptureControl:
    """The Capture panel's options and the capture waiting for the next frame.

    Parameters
    ----------
    ctx
        The window's context (its screen is read).
    session
        Its HDR frame is an EXR capture.
    control
        The scene's label names the file.
    choice
        The method on show names the file.
    grid
        In the grid view a capture is the grid's PNG.
    status
        Where saved files and failures are reported.
    """

    def __init__(
        self,
        ctx: moderngl.Context,
        session: RenderSession,
        control: SceneControl,
        choice: MethodChoice,
        grid: GridState,
        status: StatusLine,
    ):
        self.ctx = ctx
        self.session = session
        self.control = control
        self.choice = choice
        self.grid = grid
        self.status = status
        self.options = CaptureOptions(str(default_captures_dir()))
        self._pending: CaptureRequest | None = None

    def request(self, fmt: str) -> None:
        """Take a capture of ``fmt`` during the next frame."""
        if self.grid.on and fmt != "png":
            self.status.error(f"grid view: {fmt} capture is of one method; click its tile first")
            return
        label = "grid" if self.grid.on else self.choice.name
        try:
            path = capture_path(self.options.folder, self.control.scene_label, label, fmt)
        except UserError as exc:
            self.status.error(str(exc))
            return
        self._pending = CaptureRequest(path, self.options.with_ui and fmt == "png")

    def take_pending(self) -> CaptureRequest | None:
        """The capture asked for since the last frame (None: none); it is no longer pending."""
        request, self._pending = self._pending, None
        return request

    def take(
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
