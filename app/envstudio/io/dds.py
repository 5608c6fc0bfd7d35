"""DirectDraw Surface output: a cube map with its mip chain, DX10 header, RGBA16F or RGBA8.

The layout (Microsoft's "DDS file layout for cubic environment maps"): the
magic ``DDS ``, DDS_HEADER (124 bytes), DDS_HEADER_DXT10 (20 bytes), then for
each face in the order +X, −X, +Y, −Y, +Z, −Z its whole mip chain, largest
level first, each level its rows top to bottom, each texel four channels R, G,
B, A (A = 1): IEEE half floats (DXGI_FORMAT_R16G16B16A16_FLOAT, linear HDR, the
default) or bytes (DXGI_FORMAT_R8G8B8A8_UNORM, linear, clamped to [0, 1]: an LDR
file that every DDS reader opens). Face k of a DDS cube is the image OpenGL
reads as face k (engines upload them as they are), and core.cubemap's face
arrays are in the same order and orientation, so no face is flipped or swapped.

Readers: OpenImageIO 3.2 reads no floating-point DDS ("Unsupported DXGI format:
10" with the DX10 header, "Unsupported compression type: 113" with the legacy
FourCC D3DFMT_A16B16G16R16F; its only HDR format is the compressed BC6H), so the
RGBA16F file is checked by a reader written from Microsoft's layout, and the
RGBA8 file, written by the same code but for the texel encoding, by OpenImageIO
(tests/test_prefilter.py).
"""

from __future__ import annotations

import os
import struct
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import numpy.typing as npt

from envstudio.io.atomic import atomic_path
from envstudio.io.images import HALF_MAX

__all__ = [
    "DXGI_FORMAT_R8G8B8A8_UNORM",
    "DXGI_FORMAT_R16G16B16A16_FLOAT",
    "PIXEL_FORMATS",
    "write_dds_cube",
]

DXGI_FORMAT_R16G16B16A16_FLOAT = 10
DXGI_FORMAT_R8G8B8A8_UNORM = 28
#: ``pixel_format`` → (DXGI format, bytes a texel).
PIXEL_FORMATS = {
    "rgba16f": (DXGI_FORMAT_R16G16B16A16_FLOAT, 8),
    "rgba8": (DXGI_FORMAT_R8G8B8A8_UNORM, 4),
}
_DDSD = 0x1 | 0x2 | 0x4 | 0x8 | 0x1000 | 0x20000  # CAPS HEIGHT WIDTH PITCH PIXELFORMAT MIPMAPCOUNT
_DDPF_FOURCC = 0x4
_DDSCAPS = 0x8 | 0x1000 | 0x400000  # COMPLEX TEXTURE MIPMAP
_DDSCAPS2_CUBEMAP_ALLFACES = 0x200 | 0xFC00
_D3D10_RESOURCE_DIMENSION_TEXTURE2D = 3
_D3D10_RESOURCE_MISC_TEXTURECUBE = 0x4


def write_dds_cube(
    path: str | os.PathLike, levels: Sequence[npt.ArrayLike], pixel_format: str = "rgba16f"
) -> Path:
    """Write a cube map and its mip chain as a DX10 DDS file, atomically.

    Parameters
    ----------
    path
        Output ``.dds``.
    levels
        Mip levels, largest first: level k a (6, n_k, n_k, 3) array of linear
        radiance in core.cubemap's face order, n_k = max(1, n_0 >> k).
    pixel_format
        ``"rgba16f"`` (half floats) or ``"rgba8"`` (bytes, round(255 · clamp(v, 0, 1))).

    Returns
    -------
    Path
        ``path``.
    """
    if pixel_format == "rgba16f":
        brightest = max(float(np.abs(np.asarray(level)).max()) for level in levels)
        if brightest > HALF_MAX:
            print(
                f"envstudio: note: {path}: values up to {brightest:.3g} clamped to "
                f"{HALF_MAX:g}, the half floats' range",
                file=sys.stderr,
            )
    if pixel_format not in PIXEL_FORMATS:
        raise ValueError(f"pixel_format {pixel_format!r}: expected one of {sorted(PIXEL_FORMATS)}")
    dxgi, texel_bytes = PIXEL_FORMATS[pixel_format]
    arrays = [np.asarray(level, dtype=np.float32) for level in levels]
    n = arrays[0].shape[1]
    for k, level in enumerate(arrays):
        expected = (6, max(1, n >> k), max(1, n >> k), 3)
        if level.shape != expected:
            raise ValueError(f"mip level {k} must be {expected}, got {level.shape}")
    pixel_format_block = struct.pack("<II4s5I", 32, _DDPF_FOURCC, b"DX10", 0, 0, 0, 0, 0)
    header = (
        struct.pack("<7I", 124, _DDSD, n, n, n * texel_bytes, 0, len(arrays))
        + bytes(44)
        + pixel_format_block
        + struct.pack("<5I", _DDSCAPS, _DDSCAPS2_CUBEMAP_ALLFACES, 0, 0, 0)
    )
    dx10 = struct.pack(
        "<5I",
        dxgi,
        _D3D10_RESOURCE_DIMENSION_TEXTURE2D,
        _D3D10_RESOURCE_MISC_TEXTURECUBE,
        1,
        0,
    )
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        f.write(b"DDS " + header + dx10)
        for face in range(6):
            for level in arrays:
                rgba = np.concatenate([level[face], np.ones((*level.shape[1:3], 1))], axis=-1)
                f.write(_encode(rgba, pixel_format))
    return Path(path)


def _encode(rgba: np.ndarray, pixel_format: str) -> bytes:
    """The texels of one face level as the file stores them (half floats clamped to their
    range: :func:`write_dds_cube` says when it clamps)."""
    if pixel_format == "rgba16f":
        return np.clip(rgba, -HALF_MAX, HALF_MAX).astype("<f2").tobytes()
    return np.rint(np.clip(rgba, 0.0, 1.0) * 255.0).astype(np.uint8).tobytes()
