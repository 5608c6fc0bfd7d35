"""One atlas at a time in a folder: an exclusive lock on ``.atlas.lock`` naming its process."""

from __future__ import annotations

import contextlib
import fcntl
import os
from collections.abc import Iterator
from pathlib import Path

from envstudio.errors import OutputFileError

__all__ = ["LOCK_NAME", "folder_lock"]

#: The lock file in the atlas folder: the holder's process id.
LOCK_NAME = ".atlas.lock"


@contextlib.contextmanager
def folder_lock(folder: Path) -> Iterator[None]:
    """Hold ``folder``'s lock while the block runs (released when the process ends too).

    Raises
    ------
    OutputFileError
        Another process holds it: one line naming that process.
    """
    path = Path(folder) / LOCK_NAME
    with open(path, "a+", encoding="utf-8") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.seek(0)
            holder = handle.read().strip() or "unknown"
            raise OutputFileError(
                f"{folder}: another atlas (process {holder}) is measuring into it; "
                "wait for it to finish or choose another --out"
            ) from None
        handle.truncate(0)
        handle.write(str(os.getpid()))
        handle.flush()
        yield
