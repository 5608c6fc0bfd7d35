"""The entries of an atlas folder: read them whatever they hold, write them strictly.

Every file and folder the atlas reads back or writes goes through
:func:`read_json`, :func:`make_folder` or :func:`free_file`: an entry that is
unreadable or of the wrong shape (truncated, empty, binary, another JSON value, a
folder where a file belongs or the other way round) is set aside as
``NAME.corrupt`` (``NAME.corrupt-2``, ... when taken), one note says so, and the
caller measures what it held again. :func:`write_json` writes atomically and
refuses NaN and Infinity (not JSON: browsers reject them).
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path

from envstudio.io.atomic import write_text_atomic

__all__ = ["free_file", "make_folder", "read_json", "set_aside", "write_json"]


def read_json(path: Path, valid: Callable[[object], bool], notes: list[str]) -> object | None:
    """The JSON value in ``path``; None if there is none, or it was set aside.

    Parameters
    ----------
    path
        The file.
    valid
        Whether a parsed value has the shape the caller expects.
    notes
        Gets one line when the entry is set aside.
    """
    if not os.path.lexists(path):
        return None
    try:
        value = json.loads(path.read_bytes().decode("utf-8"), parse_constant=_refuse)
    except (OSError, UnicodeDecodeError, ValueError) as error:
        set_aside(path, _reason(error), notes)
        return None
    if not valid(value):
        set_aside(path, "not the expected content", notes)
        return None
    return value


def make_folder(path: Path, notes: list[str]) -> Path:
    """``path`` as a folder (made if missing); anything else there is set aside first."""
    if os.path.lexists(path) and not path.is_dir():
        set_aside(path, "not a folder", notes)
    path.mkdir(parents=True, exist_ok=True)
    return path


def free_file(path: Path, notes: list[str]) -> Path:
    """``path`` free for a file to be written: a folder (or other non-file) there is set aside."""
    if os.path.lexists(path) and not path.is_file():
        set_aside(path, "not a file", notes, "written again")
    return path


def set_aside(path: Path, reason: str, notes: list[str], then: str = "measured again") -> Path:
    """Rename ``path`` to a free ``NAME.corrupt*`` beside it and note why and ``then``."""
    aside, count = path.with_name(f"{path.name}.corrupt"), 1
    while os.path.lexists(aside):
        count += 1
        aside = path.with_name(f"{path.name}.corrupt-{count}")
    os.replace(path, aside)
    notes.append(f"{path}: {reason}; set aside as {aside.name}, {then}")
    return aside


def write_json(path: Path, value: object, indent: int | None = None) -> None:
    """Write ``value`` as strict JSON, atomically; ValueError on NaN or Infinity."""
    write_text_atomic(path, json.dumps(value, indent=indent, allow_nan=False))


def _refuse(name: str) -> None:
    raise ValueError(f"{name} is not JSON")


def _reason(error: Exception) -> str:
    if isinstance(error, IsADirectoryError):
        return "a folder, expected a file"
    if isinstance(error, UnicodeDecodeError):
        return "not text"
    text = str(error).splitlines()[0] if str(error) else type(error).__name__
    return f"unreadable ({text})"
