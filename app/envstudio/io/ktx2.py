"""KTX 2.0 output: a cube map with its mip chain, R16G16B16A16_SFLOAT, not supercompressed.

Written from the Khronos KTX 2.0 specification (KhronosGroup/KTX-Specification, ktxspec.adoc,
§3 "File Structure", §4 "Field Descriptions", §5 "Predefined Key/Value Pairs", Cubemap
Orientation appendix) and, for the Data Format Descriptor, the Khronos Data Format
Specification's basic descriptor block as libktx builds it for an unpacked little-endian
format (KTX-Software lib/dfdutils/createdfd.c). All numbers little-endian::

    identifier       «KTX 20»\\r\\n\\x1A\\n (12 bytes)
    header           vkFormat 97, typeSize 2, pixelWidth n, pixelHeight n, pixelDepth 0,
                     layerCount 0, faceCount 6, levelCount K, supercompressionScheme 0
    index            dfdByteOffset, dfdByteLength, kvdByteOffset, kvdByteLength (UInt32),
                     sgdByteOffset 0, sgdByteLength 0 (UInt64)
    level index      K × (byteOffset, byteLength, uncompressedByteLength) UInt64,
                     level 0 (the largest) first
    DFD              dfdTotalSize 92, then one basic block of 88 bytes (below)
    key/value data   sorted by key, each UInt32 length + key NUL value, padded to 4
    mip level array  level K − 1 (the smallest) first ... level 0 last, each at an
                     offset aligned to lcm(texel block size 8, 4) = 8; in a level the six
                     faces +X, −X, +Y, −Y, +Z, −Z, each its rows top to bottom

The DFD block (KDF 1.3 §5): vendorId 0 | descriptorType 0; versionNumber 2, blockSize
24 + 4 × 16; colorModel RGBSDA (1), colorPrimaries BT709 (1), transferFunction LINEAR (1),
flags ALPHA_STRAIGHT (0); texelBlockDimension 0, 0, 0, 0 (1 × 1 × 1 × 1); bytesPlane0 8;
then four samples R, G, B, A (channel ids 0, 1, 2, 15), each bitOffset 16 i, bitLength 15
(16 bits), qualifiers FLOAT | SIGNED (0xC0), samplePosition 0, sampleLower −1.0f
(0xBF800000), sampleUpper 1.0f (0x3F800000).

Faces: the KTX cube is the Vulkan/OpenGL cube sampler's (faceCount: "+X, −X, +Y, −Y, +Z,
−Z ... orientation rd", the first texel of a face at its top left), which is core.cubemap's
face order and orientation: face k of the file is the image OpenGL reads as face k, as in
io.dds, and ``KTXorientation`` says ``rd``. Texels are RGBA half floats, A = 1, values
clamped to the half range (noted on stderr, as io.dds does).
"""

from __future__ import annotations

import os
import struct
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import numpy.typing as npt

from envstudio.io.atomic import atomic_path
from envstudio.io.images import HALF_MAX

__all__ = ["IDENTIFIER", "VK_FORMAT_R16G16B16A16_SFLOAT", "dfd_rgba16f", "write_ktx2_cube"]

#: The file identifier (ktxspec §4.1).
IDENTIFIER = bytes([0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A])
#: VkFormat of RGBA 16-bit floats.
VK_FORMAT_R16G16B16A16_SFLOAT = 97
_TEXEL_BYTES = 8
_HEADER_BYTES = 12 + 9 * 4 + 4 * 4 + 2 * 8  # identifier, header, index: 80
_LEVEL_ENTRY_BYTES = 3 * 8
# Khronos Data Format constants (khr_df.h).
_KHR_DF_MODEL_RGBSDA = 1
_KHR_DF_PRIMARIES_BT709 = 1
_KHR_DF_TRANSFER_LINEAR = 1
_KHR_DF_VERSIONNUMBER_1_3 = 2
_KHR_DF_SAMPLE_DATATYPE_FLOAT_SIGNED = 0x80 | 0x40
_CHANNELS = (0, 1, 2, 15)  # R, G, B, A in the RGBSDA model
_FLOAT_MINUS_ONE = 0xBF800000
_FLOAT_ONE = 0x3F800000


def dfd_rgba16f() -> bytes:
    """The Data Format Descriptor of VK_FORMAT_R16G16B16A16_SFLOAT, dfdTotalSize included."""
    block_size = 24 + 16 * len(_CHANNELS)
    block = struct.pack(
        "<IHH4B4B8B",
        0,  # vendorId KHRONOS (17 bits) | descriptorType BASICFORMAT (15 bits)
        _KHR_DF_VERSIONNUMBER_1_3,
        block_size,
        _KHR_DF_MODEL_RGBSDA,
        _KHR_DF_PRIMARIES_BT709,
        _KHR_DF_TRANSFER_LINEAR,
        0,  # flags: ALPHA_STRAIGHT
        *(0, 0, 0, 0),  # texelBlockDimension0..3: 1 × 1 × 1 × 1
        _TEXEL_BYTES,  # bytesPlane0
        *(0,) * 7,
    )
    for i, channel in enumerate(_CHANNELS):
        block += struct.pack(
            "<HBB4BII",
            16 * i,  # bitOffset
            15,  # bitLength − 1
            channel | _KHR_DF_SAMPLE_DATATYPE_FLOAT_SIGNED,
            *(0, 0, 0, 0),  # samplePosition0..3
            _FLOAT_MINUS_ONE,
            _FLOAT_ONE,
        )
    return struct.pack("<I", 4 + len(block)) + block


def _key_values(pairs: Mapping[str, str]) -> bytes:
    """Key/value data: sorted by the keys' code points, values NUL-terminated UTF-8, each
    pair padded to 4 bytes (ktxspec §4.6)."""
    out = b""
    for key in sorted(pairs):
        if key.startswith(("KTX", "ktx")) and key not in ("KTXorientation", "KTXwriter"):
            raise ValueError(f"key {key!r}: keys starting KTX/ktx are reserved")
        entry = key.encode("utf-8") + b"\0" + str(pairs[key]).encode("utf-8") + b"\0"
        out += struct.pack("<I", len(entry)) + entry + b"\0" * (-len(entry) % 4)
    return out


def write_ktx2_cube(
    path: str | os.PathLike,
    levels: Sequence[npt.ArrayLike],
    metadata: Mapping[str, str] | None = None,
) -> Path:
    """Write a cube map and its mip chain as KTX 2.0 (RGBA16F), atomically.

    Parameters
    ----------
    path
        Output ``.ktx2``.
    levels
        Mip levels, largest first: level k a (6, n_k, n_k, 3) array of linear radiance
        in core.cubemap's face order, n_k = max(1, n_0 >> k).
    metadata
        Key/value pairs stored as NUL-terminated UTF-8 strings beside ``KTXorientation``
        (``rd``) and ``KTXwriter``; keys must not start with KTX/ktx.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        A level of the wrong shape, or a reserved key.
    """
    arrays = [np.asarray(level, dtype=np.float32) for level in levels]
    n = arrays[0].shape[1]
    for k, level in enumerate(arrays):
        expected = (6, max(1, n >> k), max(1, n >> k), 3)
        if level.shape != expected:
            raise ValueError(f"mip level {k} must be {expected}, got {level.shape}")
    brightest = max(float(np.abs(level).max()) for level in arrays)
    if brightest > HALF_MAX:
        print(
            f"envstudio: note: {path}: values up to {brightest:.3g} clamped to "
            f"{HALF_MAX:g}, the half floats' range",
            file=sys.stderr,
        )
    pairs = {"KTXorientation": "rd", "KTXwriter": "envstudio prefilter"}
    pairs.update(metadata or {})
    kvd = _key_values(pairs)
    dfd = dfd_rgba16f()
    count = len(arrays)
    dfd_offset = _HEADER_BYTES + count * _LEVEL_ENTRY_BYTES
    kvd_offset = dfd_offset + len(dfd)
    data = [_encode(level) for level in arrays]
    # Mip level array: smallest level first, each aligned to lcm(8, 4) = 8.
    offsets = [0] * count
    cursor = kvd_offset + len(kvd)
    for k in reversed(range(count)):
        cursor += -cursor % _TEXEL_BYTES
        offsets[k] = cursor
        cursor += len(data[k])
    header = IDENTIFIER + struct.pack(
        "<9I4I2Q",
        VK_FORMAT_R16G16B16A16_SFLOAT,
        2,  # typeSize: bytes of one component
        n,
        n,
        0,  # pixelDepth
        0,  # layerCount: not an array
        6,  # faceCount
        count,
        0,  # supercompressionScheme: none
        dfd_offset,
        len(dfd),
        kvd_offset,
        len(kvd),
        0,
        0,
    )
    index = b"".join(
        struct.pack("<3Q", offsets[k], len(data[k]), len(data[k])) for k in range(count)
    )
    with atomic_path(path, need=cursor) as tmp, open(tmp, "wb") as f:
        f.write(header + index + dfd + kvd)
        for k in reversed(range(count)):
            f.write(b"\0" * (offsets[k] - f.tell()))
            f.write(data[k])
    return Path(path)


def _encode(level: np.ndarray) -> bytes:
    """One level's six faces as RGBA half floats (A = 1), clamped to the half range."""
    rgba = np.concatenate([level, np.ones((*level.shape[:3], 1), np.float32)], axis=-1)
    return np.clip(rgba, -HALF_MAX, HALF_MAX).astype("<f2").tobytes()
