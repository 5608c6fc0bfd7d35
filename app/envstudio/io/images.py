"""Image files through OpenImageIO: HDR environments in, EXR and PNG out (atomically).

Arrays follow image order: row 0 is the top of the picture. Pixel values are
linear float32 RGB unless a function says otherwise.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

import numpy as np
import numpy.typing as npt
import OpenImageIO as oiio

from envstudio.errors import InputFileError
from envstudio.io.atomic import atomic_path, check_output_path

HDR_SUFFIXES = (".exr", ".hdr")
#: The largest magnitude a half float holds; an EXR with larger values is written in float32.
HALF_MAX = 65504.0
#: Radiance past this is refused as out of range: far above any capture (the sun's disc is
#: about 1.6e9 cd/m²), and its squares would overflow the float32 sums the methods make.
MAX_RADIANCE = 1e12
LDR_SUFFIXES = (".png", ".jpg", ".jpeg")


def read_image(path: str | os.PathLike) -> npt.NDArray[np.float32]:
    """Read an image file as float32.

    Returns
    -------
    (h, w, c) float32
        Pixel values as stored (linear for EXR/HDR), ``c`` channels.

    Raises
    ------
    InputFileError
        If the file is missing, not an image, or truncated.
    """
    path = Path(path)
    if not path.is_file():
        raise InputFileError(f"{path}: no such file (expected an .exr or .hdr image)")
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        reason = oiio.geterror().strip().splitlines()
        detail = reason[0] if reason else "unknown format"
        raise InputFileError(f"{path}: not a readable image ({detail})")
    try:
        pixels = inp.read_image("float")
        error = inp.geterror() if pixels is None else ""
    finally:
        inp.close()
    if pixels is None or pixels.size == 0:
        detail = error.strip().splitlines()[0] if error.strip() else "no pixel data"
        raise InputFileError(f"{path}: truncated or corrupt image ({detail})")
    pixels = np.asarray(pixels, dtype=np.float32)
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    return pixels


def read_environment(path: str | os.PathLike) -> npt.NDArray[np.float32]:
    """Read a lat-long HDR environment (.exr or .hdr).

    Negative values left by lossy compression are clamped to 0; grey images are
    expanded to RGB; alpha is dropped.

    Returns
    -------
    (h, w, 3) float32
        Linear radiance, ``w == 2 * h``, row 0 looking up (+Y).

    Raises
    ------
    InputFileError
        If the file is unreadable, not 2:1, or holds NaN/Inf pixels.
    """
    path = Path(path)
    pixels = read_image(path)
    h, w, c = pixels.shape
    if w != 2 * h:
        raise InputFileError(f"{path}: lat-long map is {w}x{h}, expected width = 2 x height")
    bad = ~np.isfinite(pixels)
    if not bad.any() and float(np.abs(pixels).max(initial=0.0)) > MAX_RADIANCE:
        y, x = np.argwhere(np.abs(pixels).max(axis=2) > MAX_RADIANCE)[0]
        raise InputFileError(
            f"{path}: radiance {float(np.abs(pixels[y, x]).max()):.3g} at x={x}, y={y} is out "
            f"of range (expected at most {MAX_RADIANCE:g})"
        )
    if bad.any():
        y, x = np.argwhere(bad.any(axis=2))[0]
        raise InputFileError(
            f"{path}: {int(bad.any(axis=2).sum())} pixels are NaN or Inf "
            f"(first at x={x}, y={y}); expected finite radiance"
        )
    rgb = np.repeat(pixels[:, :, :1], 3, axis=2) if c < 3 else pixels[:, :, :3]
    return np.ascontiguousarray(np.maximum(rgb, 0.0), dtype=np.float32)


def write_image(path: str | os.PathLike, pixels: npt.ArrayLike) -> Path:
    """Write an image atomically; the format follows the suffix.

    Parameters
    ----------
    path
        ``.exr``/``.hdr`` get linear float data (EXR with ZIP compression, as half
        float where every value fits, else as float32: a bright sun stays finite);
        ``.png``/``.jpg`` expect display values in [0, 1] (float) or uint8 and are
        stored as 8-bit.
    pixels
        (h, w) or (h, w, c) array, row 0 at the top.

    Raises
    ------
    InputFileError
        If the folder does not exist or the suffix is not an image format.
    OutputFileError
        If the file cannot be written whole (a full disk, a read-only folder);
        an existing file of that name is then left as it was.
    """
    path = check_output_path(path)
    suffix = path.suffix.lower()
    data = np.asarray(pixels)
    if data.ndim == 2:
        data = data[:, :, None]
    if suffix in HDR_SUFFIXES:
        data = np.ascontiguousarray(data, dtype=np.float32)
        fits_half = float(np.nan_to_num(np.abs(data), posinf=np.inf).max(initial=0.0)) <= HALF_MAX
        fmt = "half" if suffix == ".exr" and fits_half else "float"
    elif suffix in LDR_SUFFIXES:
        if data.dtype != np.uint8:
            data = np.clip(np.nan_to_num(data.astype(np.float32)) * 255.0 + 0.5, 0, 255)
        data = np.ascontiguousarray(data, dtype=np.uint8)
        fmt = "uint8"
    else:
        raise InputFileError(f"{path}: unknown image type {suffix!r}, expected .png, .exr or .hdr")
    h, w, c = data.shape
    spec = oiio.ImageSpec(w, h, c, fmt)
    if suffix == ".exr":
        spec.attribute("compression", "zip")
    with atomic_path(path, need=data.nbytes) as tmp:
        out = oiio.ImageOutput.create(str(tmp))
        if out is None or not out.open(str(tmp), spec):
            raise OSError(errno.EIO, f"cannot write: {oiio.geterror().strip()}")
        ok = out.write_image(data)
        ok = out.close() and ok
        if not ok or not _complete(tmp, spec):
            raise OSError(errno.EIO, f"cannot write: {out.geterror().strip() or 'incomplete'}")
    return path


def _complete(path: Path, spec) -> bool:
    """Whether the image file at ``path`` reads back whole with ``spec``'s size."""
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        oiio.geterror()  # taken, so OpenImageIO does not print it at exit
        return False
    try:
        shape = (inp.spec().width, inp.spec().height, inp.spec().nchannels)
        pixels = inp.read_image()
        if pixels is None:
            inp.geterror()
    finally:
        inp.close()
    return pixels is not None and shape == (spec.width, spec.height, spec.nchannels)
