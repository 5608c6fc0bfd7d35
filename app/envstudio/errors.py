"""User-facing errors: one line naming the file or value and what was expected.

Every error a user can cause (bad file, bad value, no display) is raised as a
subclass of :class:`UserError`; the CLI prints ``str(error)`` on one line and
exits with :attr:`UserError.exit_code`, the viewer shows it in the UI and keeps
the previous state. An operating-system error on a named file (missing, a name
too long, no permission) is the user's too: :func:`file_error` gives its line.
Anything else is a bug and keeps its traceback.
"""


class UserError(Exception):
    """An error caused by input the user gave; printed as one line, never a traceback."""

    exit_code = 2


class InputFileError(UserError):
    """A file is missing, unreadable or not what was expected."""


class OutputFileError(UserError):
    """A file cannot be written: a folder given as a file, a read-only folder, a full disk."""


class ParameterError(UserError):
    """An unknown method or parameter, or a value out of range."""


class ContextError(UserError):
    """No OpenGL context could be made (no display, no EGL)."""


def file_error(exc: OSError) -> str | None:
    """The one line for an operating-system error on a named file (``FILE: reason``), or
    None when it names no file (then it is a bug and keeps its traceback)."""
    if exc.filename is None:
        return None
    return f"{exc.filename}: {exc.strerror or exc}"
