"""Cache entries that do not load are discarded, whatever they turned into."""

from __future__ import annotations

import shutil
from pathlib import Path


def discard(path: Path) -> None:
    """Remove a cache entry that does not load: a file, a link, or a folder in its place."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)
