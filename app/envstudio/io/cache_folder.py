"""Where envstudio keeps what it can compute again: one folder, each user of it a subfolder."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["cache_folder"]

#: Environment variable naming the cache folder (a shared folder serves several machines).
CACHE_ENV = "ENVSTUDIO_CACHE_DIR"


def cache_folder(name: str | None = None) -> Path:
    """``$ENVSTUDIO_CACHE_DIR``, else the platform's user cache, or its subfolder ``name``.

    The folder is not created here. On Linux the user cache is
    ``$XDG_CACHE_HOME/envstudio``, else ``~/.cache/envstudio``.

    Parameters
    ----------
    name
        The subfolder of one kind of cached result (``"pem"``, ``"rsibr"``, ...);
        None for the cache folder itself.
    """
    import platformdirs

    root = Path(os.environ.get(CACHE_ENV) or platformdirs.user_cache_dir("envstudio"))
    return root if name is None else root / name
