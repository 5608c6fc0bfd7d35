"""Where shaders and assets live.

In a source checkout they are the top-level ``shaders/`` and ``assets/`` folders
(``app/`` is the source root); an installed wheel carries them as
``envstudio/shaders`` and ``envstudio/assets``.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

_PACKAGE_DIR = Path(__file__).resolve().parent


def _find(name: str) -> Path:
    for candidate in (_PACKAGE_DIR / name, _PACKAGE_DIR.parents[1] / name):
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(f"envstudio data folder {name!r} not found beside {_PACKAGE_DIR}")


@cache
def shader_root() -> Path:
    """Folder holding the GLSL sources (``common/`` plus one folder per method)."""
    return _find("shaders")


@cache
def asset_root() -> Path:
    """Folder holding the shipped HDR environments, meshes and scenes."""
    return _find("assets")
