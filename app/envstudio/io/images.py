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

from envstudio.errors import InputFileError, ParameterError
from envstudio.io.atomic import atomic_path, check_output_path
from envstudio.io.memory import available_memory, megabytes

HDR_SUFFIXES = (".exr", ".hdr")
#: The largest magnitude a half float holds; an EXR with larger values is written in float32.
HALF_MAX = 65504.0
#: Radiance past this is refused as out of range: far above any capture (the sun's disc is
#: about 1.6e9 cd/m²), and its squares would overflow the float32 sums the methods make.
MAX_RADIANCE = 1e12
#: Peak bytes per lat-long texel of the heaviest commands (``sh``, ``render``: about 180
#: measured at 16384 x 8192), for the memory check before a map is read.
BYTES_PER_TEXEL = 200
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
    inp = _open(path)
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


def read_environment(
    path: str | os.PathLike, max_width: int | None = None
) -> npt.NDArray[np.float32]:
    """Read a lat-long HDR environment (.exr or .hdr).

    Negative values left by lossy compression are clamped to 0; grey images are
    expanded to RGB; alpha is dropped. The memory the map will take in the
    heaviest commands (:data:`BYTES_PER_TEXEL`) is estimated from the file's
    header before its pixels are read.

    Parameters
    ----------
    path
        The file.
    max_width
        Box-filter the map, as it is read (a block of rows at a time), by the
        smallest whole factor that brings its width to at most this.

    Returns
    -------
    (h, w, 3) float32
        Linear radiance, ``w == 2 * h``, row 0 looking up (+Y).

    Raises
    ------
    InputFileError
        If the file is unreadable, not 2:1, too large for the memory available
        (naming both and the ``--max-env-width`` that fits), holds NaN/Inf pixels
        or radiance past :data:`MAX_RADIANCE`.
    """
    path = Path(path)
    if path.suffix.lower() not in HDR_SUFFIXES:
        raise InputFileError(
            f"{path}: expected a linear HDR environment (.exr or .hdr); an 8-bit image holds "
            "display values, not radiance"
        )
    if max_width is not None and not 8 <= max_width:
        raise ParameterError(f"--max-env-width {max_width}: expected a width of at least 8")
    w, h, c = _header(path)
    if w != 2 * h:
        raise InputFileError(f"{path}: lat-long map is {w}x{h}, expected width = 2 x height")
    step = 1 if max_width is None or w <= max_width else -(-w // max(int(max_width), 2))
    while h % step:
        step += 1
    need = (w // step) * (h // step) * BYTES_PER_TEXEL + step * w * c * 4
    available = available_memory()
    if need > available:
        fits = 2 ** int(np.log2(max(np.sqrt(2.0 * available / BYTES_PER_TEXEL), 2.0)))
        raise InputFileError(
            f"{path}: a {w}x{h} map needs about {megabytes(need)} of memory and "
            f"{megabytes(available)} are available; --max-env-width {fits} box-filters it "
            "as it is read"
        )
    pixels = read_image(path) if step == 1 else _box_filtered(path, step)
    h, w, c = pixels.shape
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


def _open(path: Path):
    """An ImageInput of ``path``, or the one-line error read_image gives."""
    if not path.is_file():
        raise InputFileError(f"{path}: no such file (expected an .exr or .hdr image)")
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        reason = oiio.geterror().strip().splitlines()
        detail = reason[0] if reason else "unknown format"
        raise InputFileError(f"{path}: not a readable image ({detail})")
    return inp


def _header(path: Path) -> tuple[int, int, int]:
    """(width, height, channels) from the file's header, no pixels read."""
    inp = _open(path)
    try:
        spec = inp.spec()
        return spec.width, spec.height, spec.nchannels
    finally:
        inp.close()


def _box_filtered(path: Path, step: int) -> npt.NDArray[np.float32]:
    """The image box-filtered by ``step`` in both directions, read ``step`` rows at a time."""
    inp = _open(path)
    try:
        spec = inp.spec()
        w, h, c = spec.width, spec.height, spec.nchannels
        out = np.empty((h // step, w // step, c), np.float32)
        for row in range(h // step):
            block = inp.read_scanlines(row * step, (row + 1) * step, 0, 0, c, "float")
            if block is None:
                detail = inp.geterror().strip().splitlines()
                raise InputFileError(
                    f"{path}: truncated or corrupt image ({detail[0] if detail else 'no data'})"
                )
            block = np.asarray(block, np.float32).reshape(step, w // step, step, c)
            out[row] = block.mean(axis=(0, 2))
        return out
    finally:
        inp.close()


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
