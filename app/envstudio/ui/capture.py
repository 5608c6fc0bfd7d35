"""Screenshots: PNG as displayed (with or without the UI) or EXR (linear HDR, before tone mapping).

Files are named ``<scene>-<method>-<YYYYmmdd-HHMMSS>.<ext>`` in the captures
folder (``<user pictures>/envmap-studio`` by default) and written atomically by
:func:`envstudio.io.images.write_image`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import moderngl
import numpy as np
import numpy.typing as npt
import platformdirs

from envstudio.errors import InputFileError
from envstudio.io.images import write_image
from envstudio.ui.settings import APP_NAME

FORMATS = ("png", "exr")


def default_captures_dir() -> Path:
    """``<user pictures folder>/envmap-studio`` (not created here)."""
    return Path(platformdirs.user_pictures_dir()) / APP_NAME


@dataclass
class CaptureRequest:
    """A capture to take during the next frame.

    Attributes
    ----------
    path : Path
        Destination file; its suffix is the format.
    with_ui : bool
        PNG only: read the window after the UI is drawn rather than before.
    """

    path: Path
    with_ui: bool

    @property
    def is_hdr(self) -> bool:
        """EXR: the linear frame, never with the UI."""
        return self.path.suffix.lower() == ".exr"


def capture_path(folder: str | Path, scene: str, method: str, fmt: str) -> Path:
    """A new file name in ``folder`` (created if missing) for a capture of ``fmt``.

    Raises
    ------
    InputFileError
        If ``fmt`` is unknown or the folder cannot be created.
    """
    if fmt not in FORMATS:
        raise InputFileError(f"capture format {fmt!r}: expected one of {', '.join(FORMATS)}")
    folder = Path(folder).expanduser()
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputFileError(f"{folder}: cannot create captures folder ({exc.strerror})") from None
    stem = f"{scene}-{method}-{time.strftime('%Y%m%d-%H%M%S')}"
    path = folder / f"{stem}.{fmt}"
    number = 1
    while path.exists():
        number += 1
        path = folder / f"{stem}-{number}.{fmt}"
    return path


def read_framebuffer(
    fbo: moderngl.Framebuffer, size: tuple[int, int], origin: tuple[int, int] = (0, 0)
) -> npt.NDArray[np.uint8]:
    """(h, w, 3) uint8 of the ``size`` pixels of ``fbo`` from ``origin`` (its lower-left
    corner, GL pixels), row 0 at the top."""
    width, height = size
    data = fbo.read(viewport=(*origin, width, height), components=3, alignment=1)
    return np.frombuffer(data, dtype=np.uint8).reshape(height, width, 3)[::-1]


def save(path: Path, pixels: npt.ArrayLike) -> Path:
    """Write ``pixels`` atomically; raises InputFileError with a one-line reason."""
    try:
        return write_image(path, pixels)
    except OSError as exc:
        raise InputFileError(f"{path}: cannot write capture ({exc.strerror})") from None
