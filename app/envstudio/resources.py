"""Where shaders and assets live.

An installed wheel (and the PyInstaller bundle) carries them as package data,
``envstudio/shaders`` and ``envstudio/assets``, found through
``importlib.resources``; setup.py copies them there at build time. In a source
checkout (an editable install) they are the top-level ``shaders/`` and
``assets/`` folders beside ``app/``, the source root. The package's own folders
come first, so an installed envstudio never reads a checkout it happens to sit in.
"""

from __future__ import annotations

from functools import cache
from importlib.resources import files
from pathlib import Path

_CHECKOUT = Path(__file__).resolve().parents[2]


def _find(name: str) -> Path:
    # Callers open the files by path (OpenImageIO, trimesh, #include resolution), so the
    # package must be unpacked on disk: a regular install, a bundle, or the checkout.
    packaged = files("envstudio") / name
    candidates = [packaged] if isinstance(packaged, Path) else []
    candidates.append(_CHECKOUT / name)
    for candidate in candidates:
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(
        f"envstudio data folder {name!r} not found in the package ({packaged}) "
        f"nor in a checkout ({_CHECKOUT / name}); reinstall envmap-studio"
    )


@cache
def shader_root() -> Path:
    """Folder holding the GLSL sources (``common/`` plus one folder per method)."""
    return _find("shaders")


@cache
def asset_root() -> Path:
    """Folder holding the shipped HDR environments, meshes and scenes."""
    return _find("assets")
