"""Opening the GLFW window (OpenGL 3.3 core) with one-line errors, and file drops.

moderngl-window 3.1.1's GLFW backend never registers GLFW's drop callback, so
``WindowConfig.on_files_dropped_event`` would never fire; :func:`open_window`
connects it. GLFW errors are logged (debug level) instead of pyGLFW's default
warnings, and the last one explains a failure to open the window.
"""

from __future__ import annotations

import logging

import glfw
from moderngl_window.context.base import BaseWindow
from moderngl_window.context.glfw import Window

from envstudio.errors import ContextError

GL_VERSION = (3, 3)

_log = logging.getLogger(__name__)


class _GlfwErrors:
    """GLFW error callback remembering the latest description."""

    def __init__(self):
        self.last = ""

    def __call__(self, code: int, description: bytes | str) -> None:
        if isinstance(description, bytes):
            description = description.decode("utf-8", errors="replace")
        self.last = description
        _log.debug("GLFW error %d: %s", code, description)


def open_window(size: tuple[int, int], title: str) -> BaseWindow:
    """Open a resizable window of ``size`` (width, height) points with a GL 3.3 core context.

    The window forwards dropped files to its config's ``on_files_dropped_event``.

    Raises
    ------
    ContextError
        ``no display ...`` when GLFW cannot reach a display server, or when the
        driver offers no OpenGL 3.3 core context.
    """
    errors = _GlfwErrors()
    glfw.set_error_callback(errors)
    if not glfw.init():
        raise ContextError(
            f"no display: cannot open a window ({errors.last or 'GLFW failed to initialise'}); "
            "set DISPLAY, or render without a window with `envstudio render`"
        )
    try:
        window = Window(title=title, size=size, gl_version=GL_VERSION, resizable=True, vsync=True)
    except Exception as exc:
        glfw.terminate()
        detail = errors.last or str(exc).strip().splitlines()[0]
        raise ContextError(
            f"no display with OpenGL {GL_VERSION[0]}.{GL_VERSION[1]} core: cannot open a window "
            f"({detail})"
        ) from None
    handle = glfw.get_current_context()

    def dropped(_handle, paths: list[str]) -> None:
        x, y = glfw.get_cursor_pos(handle)
        window.files_dropped_event_func(int(x), int(y), list(paths))

    glfw.set_drop_callback(handle, dropped)
    return window
