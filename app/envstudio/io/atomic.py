"""Atomic file writes: a temporary file in the target folder, checked, then a rename.

Nothing is lost on a failing disk: the temporary file is flushed to the disk
(``fsync``) and checked before it replaces the target, so a full disk, a
read-only folder or a writer that gave up leaves the old file as it was and
raises :class:`~envstudio.errors.OutputFileError`, one line naming the file,
what went wrong and, on a full disk, the space.
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from envstudio.errors import InputFileError, OutputFileError, ParameterError


def check_output_path(path: str | os.PathLike, suffixes: tuple[str, ...] = ()) -> Path:
    """Return ``path`` as a Path after checking a file can be written there.

    Called once, up front, by every command that writes (through
    :func:`atomic_path` too), so bad output paths fail before any work.

    Parameters
    ----------
    path
        The file to write.
    suffixes
        The suffixes it may have (any when empty), e.g. ``(".json",)``.

    Raises
    ------
    InputFileError
        If the parent folder does not exist.
    ParameterError
        If ``path`` has none of ``suffixes``.
    OutputFileError
        If ``path`` is a folder, or its folder cannot be written (read-only).
    """
    path = Path(path)
    if suffixes and path.suffix.lower() not in suffixes:
        raise ParameterError(f"{path}: expected a {' or '.join(suffixes)} file name")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise InputFileError(f"{path}: folder {parent} does not exist")
    if path.is_dir():
        raise OutputFileError(f"{path}: is a folder, expected a file name to write")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputFileError(
            f"{path}: folder {parent} is not writable (read-only or no permission)"
        )
    return path


def check_output_folder(path: str | os.PathLike) -> Path:
    """Return ``path`` as a Path after checking a folder of files can be written there
    (it exists as a folder, or can be made in a writable folder).

    Raises
    ------
    InputFileError
        If the parent folder does not exist.
    OutputFileError
        If ``path`` is a file, or the folder that would hold it or its files is read-only.
    """
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise InputFileError(f"{path}: folder {parent} does not exist")
    if path.exists() and not path.is_dir():
        raise OutputFileError(f"{path}: is a file, expected a folder for the report")
    where = path if path.is_dir() else parent
    if not os.access(where, os.W_OK | os.X_OK):
        raise OutputFileError(
            f"{path}: folder {where} is not writable (read-only or no permission)"
        )
    return path


def _megabytes(count: int) -> str:
    return f"{count / 2**20:.1f} MB" if count >= 2**20 else f"{count / 2**10:.0f} kB"


def _failure(path: Path, error: OSError, need: int | None) -> OutputFileError:
    """One line for a write of ``path`` that failed with ``error``."""
    kept = f"; the existing {path.name} is unchanged" if path.exists() else ""
    free = shutil.disk_usage(path.parent).free
    if error.errno in (errno.ENOSPC, errno.EDQUOT) or free == 0:
        amount = f"it needs about {_megabytes(need)}, " if need else ""
        return OutputFileError(
            f"{path}: not written, the disk is full ({amount}{_megabytes(free)} free){kept}"
        )
    reason = error.strerror or str(error)
    return OutputFileError(f"{path}: not written ({reason}){kept}")


def _settle(tmp: Path, need: int | None) -> None:
    """Flush ``tmp`` to the disk and check a writer left data there and room after it.

    Raises
    ------
    OSError
        ENOSPC when the file is empty though data was due (``need`` not 0) or the
        disk has no block left: what a writer that ignored a failed write leaves.
    """
    with open(tmp, "rb+") as handle:
        os.fsync(handle.fileno())
    empty = tmp.stat().st_size == 0 and need != 0
    if empty or shutil.disk_usage(tmp.parent).free == 0:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, need: int | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` once it is complete.

    The temporary file keeps the target's suffix so writers that choose a format
    by extension (OpenImageIO) still work. On any error the temporary file is
    removed and ``path`` is untouched.

    Parameters
    ----------
    path
        The file to write.
    need
        Bytes the write will take about, named when the disk is full.

    Raises
    ------
    OutputFileError
        The folder cannot be written, the disk is full, or the write failed.
    """
    path = check_output_path(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    except OSError as error:
        raise _failure(path, error, need) from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        try:
            yield tmp_path
            _settle(tmp_path, need)
            os.chmod(tmp_path, 0o666 & ~_umask())  # mkstemp makes 0600; use the usual mode
            os.replace(tmp_path, path)
        except OSError as error:
            raise _failure(path, error, need) from None
    finally:
        tmp_path.unlink(missing_ok=True)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_path(path, need=len(text.encode("utf-8"))) as tmp:
        tmp.write_text(text, encoding="utf-8")
