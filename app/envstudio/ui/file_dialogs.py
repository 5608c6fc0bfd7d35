"""Native "Open..." dialogs through imgui-bundle's portable_file_dialogs, polled without blocking.

portable_file_dialogs runs the platform's dialog (zenity or kdialog on Linux)
as a separate process; :meth:`OpenFileDialog.poll` asks each frame whether the
user answered, waiting 0 ms, so the viewer keeps drawing meanwhile.
"""

from __future__ import annotations

import shutil
import sys
from collections.abc import Sequence
from pathlib import Path

from imgui_bundle import portable_file_dialogs as pfd

from envstudio.errors import UserError

# Programs portable_file_dialogs can drive on Linux and BSD.
_UNIX_DIALOG_PROGRAMS = ("zenity", "matedialog", "qarma", "kdialog")


class NoFileDialogError(UserError):
    """No program is installed that can show a native file dialog."""


def check_dialogs_available() -> None:
    """Raise :class:`NoFileDialogError` if no native dialog can be shown here."""
    if sys.platform in ("win32", "darwin"):
        return
    if not any(shutil.which(program) for program in _UNIX_DIALOG_PROGRAMS):
        raise NoFileDialogError(
            "no file dialog program found (install zenity or kdialog); "
            "drop the file onto the window instead"
        )


class OpenFileDialog:
    """At most one open-file dialog at a time, answered asynchronously.

    Parameters
    ----------
    title
        Dialog title.
    filter_name, suffixes
        The file type offered, e.g. ``"HDR environments"`` and ``(".exr", ".hdr")``.
    """

    def __init__(self, title: str, filter_name: str, suffixes: Sequence[str]):
        self.title = title
        patterns = " ".join(f"*{s}" for s in suffixes)
        self._filters = [f"{filter_name} ({patterns})", patterns, "All files", "*"]
        self._dialog: pfd.open_file | None = None

    @property
    def is_open(self) -> bool:
        """Whether a dialog is waiting for the user."""
        return self._dialog is not None

    def open(self) -> None:
        """Show the dialog (no-op if one is already showing).

        Raises
        ------
        NoFileDialogError
            If the platform has no dialog program.
        """
        if self._dialog is not None:
            return
        check_dialogs_available()
        self._dialog = pfd.open_file(self.title, "", self._filters)

    def poll(self) -> Path | None:
        """The chosen file once the user answered, else None (also when cancelled)."""
        if self._dialog is None or not self._dialog.ready(0):
            return None
        chosen = self._dialog.result()
        self._dialog = None
        return Path(chosen[0]) if chosen else None

    def close(self) -> None:
        """Dismiss a dialog still showing (at exit)."""
        if self._dialog is not None:
            self._dialog.kill()
            self._dialog = None
