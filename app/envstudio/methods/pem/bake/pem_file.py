"""The ``.pem`` file: one PEM bake's per-view inferred environment maps (seed 003 §3–4).

Seed 003 §3 ("System Overview") bakes, for every sample of the parameter space
(views), per reflector part, the environment maps the playback draws with; §4
("EM MIPMAPs") stores every MIP level, "encoded levels … as residuals from
corresponding decimated versions of the finest level".

File format (version 2)
-----------------------
::

    offset  size  content
    0       8     magic b"\\x93ENVPEM\\n"
    8       4     version, uint32 little-endian (2)
    12      8     H, header length, uint64 little-endian
    20      H     header, UTF-8 JSON (below)
    20 + H  …     payload: one zstd frame (PyPI ``zstandard``) per array, in the
                  header's ``arrays`` order, at the offsets it gives

The header: ``format`` ("envstudio-pem"), ``version`` (2), ``scene`` (name),
``view_space`` (ViewSpace.describe(): kind, azimuths, elevations, distance,
target, fov_y), ``views`` V, ``parts`` (the P part names), ``em_size`` n,
``levels`` L (n >> (L − 1) ≥ 1), ``models`` (model → channels: ``distant`` 3,
``local`` 4, ``sphere`` 3), ``parameters`` (size R, samples, em_size,
levels, smoothness λ, tie μ, seed, bounces, the models' geometries),
``mesh_checks`` (per part: name, vertices, triangles, sha256 of the mesh's
float32 vertices, int32 faces and model matrix, :func:`~.hull.mesh_check`),
``arrays`` (per array: name, dtype, shape, offset and length of its frame in
the payload, sha256 of its uncompressed bytes, and ``filter``: ``"shuffle"``
when the frame holds the bytes as byte planes, all first bytes of the items
then all second bytes…, as Blosc does, which zstd packs about a quarter
smaller for half floats; absent: the bytes as they are) and ``checksum``, the SHA-256 of
the header's JSON without ``checksum`` (sorted keys, compact) followed by the
whole payload.

Arrays (V views in ViewSpace.cameras() order, P parts, n_k = n >> k):

============================ ================================ ==========================
``maps/M/0``                 (V, P, 6, n, n, C) float16       model M's finest level:
                                                              linear radiance (local:
                                                              premultiplied RGBA),
                                                              OpenGL cube faces
``maps/M/k``, k = 1 … L − 1  (V, P, 6, n_k, n_k, C) float16   level k minus the k-fold
                                                              2 × 2 box decimation of
                                                              the stored finest level
``hull/p``                   (T_p,) uint8                     1 for triangles of part p
                                                              (its mesh's face order) on
                                                              the reflectors' convex hull
``psnr/M``                   (V, P) float64                   A x against the traced
                                                              layer, dB (NaN: part not
                                                              in the view)
``playback_psnr/N``          (V,) float64                     N ∈ layered, sphere,
                                                              static: predicted
                                                              playback against the
                                                              composite, dB
``cameras``                  (V, 2) float64                   azimuth, elevation, degrees
``box``                      (2, 3) float64                   distant box map: lo, hi
``origins``                  (P, 3) float64                   EM origin per part
``ellipsoids``               (P, 2, 3) float64                local ellipsoid: centre,
                                                              radii
============================ ================================ ==========================

Maps: ``distant``, ``local`` and ``sphere`` are in every file; ``ptm`` (the PTM's
per-view surface textures, issue 31) is optional, listed in the header's
``models`` when present, with its ``psnr/ptm`` and ``playback_psnr/ptm``. Files
without it (made before) are read as they are: the format's version is unchanged.

Level k is rebuilt as ``decimate^k(float32(maps/M/0)) + float32(maps/M/k)``
(:mod:`.mip`); half floats hold |x| ≤ 65504 (larger values are clipped on save).
Files are written atomically (io.atomic); :func:`load_pem` refuses with one line
a file that is not a ``.pem``, a version-1 file (re-bake), another version, a
truncated file, a checksum mismatch, and maps for fewer views or parts than the
header names.
"""

from __future__ import annotations

import hashlib
import json
import os
import struct
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt
import zstandard

from envstudio.errors import InputFileError
from envstudio.io.atomic import atomic_path
from envstudio.methods.pem.bake.lookups import CHANNELS, MODELS, PLAYBACK, REQUIRED
from envstudio.methods.pem.bake.mip import decimate

__all__ = [
    "FORMAT",
    "MAGIC",
    "VERSION",
    "PemBake",
    "decode_levels",
    "encode_levels",
    "load_pem",
    "save_pem",
]

FORMAT = "envstudio-pem"
VERSION = 2
MAGIC = b"\x93ENVPEM\n"
_PREFIX = struct.Struct("<8sIQ")
_HALF_MAX = float(np.finfo(np.float16).max)
_GEOMETRY = ("cameras", "box", "origins", "ellipsoids")


@dataclass
class PemBake:
    """A PEM bake in memory (module docstring for the meaning of each field).

    Attributes
    ----------
    scene : str
        Scene name.
    view_space : dict
        :meth:`ViewSpace.describe` of the parameter space.
    parts : list of str
        Reflector part names, P.
    parameters : dict
        Bake parameters.
    maps : dict
        Model (``distant``, ``local``, ``sphere``, and ``ptm`` where baked) → list
        over levels k of (V, P, 6, n_k, n_k, C) float32 (C = 3, 4, 3, 3), level 0
        the finest.
    hull : list of (T_p,) bool
        Per part, its triangles on the reflectors' convex hull.
    mesh_checks : list of dict
        Per part: name, vertices, triangles, sha256 (:func:`~.hull.mesh_check`).
    psnr : dict
        Model → (V, P) float64 fit PSNR.
    playback_psnr : dict
        ``layered``, ``sphere``, ``static`` → (V,) float64 predicted playback PSNR.
    cameras : (V, 2) float64
    box : (2, 3) float64
    origins : (P, 3) float64
    ellipsoids : (P, 2, 3) float64
    header : dict
        The header as read or written (empty before).
    """

    scene: str
    view_space: dict
    parts: list[str]
    parameters: dict
    maps: dict[str, list[npt.NDArray[np.float32]]]
    hull: list[npt.NDArray[np.bool_]]
    mesh_checks: list[dict]
    psnr: dict[str, npt.NDArray[np.float64]]
    playback_psnr: dict[str, npt.NDArray[np.float64]]
    cameras: npt.NDArray[np.float64]
    box: npt.NDArray[np.float64]
    origins: npt.NDArray[np.float64]
    ellipsoids: npt.NDArray[np.float64]
    header: dict = field(default_factory=dict)

    @property
    def views(self) -> int:
        """V, the number of views."""
        return int(self.cameras.shape[0])

    @property
    def em_size(self) -> int:
        """n, the finest cube face edge in texels."""
        return int(self.maps["distant"][0].shape[3])

    @property
    def levels(self) -> int:
        """L, MIP levels per map."""
        return len(self.maps["distant"])


def encode_levels(levels: list[npt.ArrayLike]) -> list[npt.NDArray[np.float16]]:
    """Half-float finest level and residuals of levels k ≥ 1 (module docstring).

    Parameters
    ----------
    levels
        L arrays (..., 6, n_k, n_k, C), level k of edge n >> k.

    Returns
    -------
    list of float16 arrays, the same shapes.
    """
    finest = np.clip(np.asarray(levels[0], np.float32), -_HALF_MAX, _HALF_MAX).astype(np.float16)
    out = [finest]
    base = finest.astype(np.float32)
    for level in levels[1:]:
        base = _decimate(base)
        res = np.asarray(level, np.float32) - base
        out.append(np.clip(res, -_HALF_MAX, _HALF_MAX).astype(np.float16))
    return out


def decode_levels(stored: list[npt.ArrayLike]) -> list[npt.NDArray[np.float32]]:
    """The inverse of :func:`encode_levels`: float32 levels."""
    base = np.asarray(stored[0]).astype(np.float32)
    out = [base]
    for res in stored[1:]:
        base = _decimate(base)
        out.append(base + np.asarray(res).astype(np.float32))
    return out


def _decimate(a: np.ndarray) -> np.ndarray:
    """:func:`.mip.decimate` over the face axes of (..., 6, n, n, C)."""
    half = decimate(a.reshape(-1, *a.shape[-3:])).astype(np.float32)
    return half.reshape(*a.shape[:-3], *half.shape[1:])


def _arrays(bake: PemBake) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    models = _models(bake.maps)
    for model in models:
        for k, level in enumerate(encode_levels(bake.maps[model])):
            out[f"maps/{model}/{k}"] = level
    for p, mask in enumerate(bake.hull):
        out[f"hull/{p}"] = np.asarray(mask, bool).astype(np.uint8)
    for model in models:
        out[f"psnr/{model}"] = np.asarray(bake.psnr[model], np.float64)
    for name in PLAYBACK:
        if name in bake.playback_psnr:
            out[f"playback_psnr/{name}"] = np.asarray(bake.playback_psnr[name], np.float64)
    for name in _GEOMETRY:
        out[name] = np.asarray(getattr(bake, name), np.float64)
    return {k: np.ascontiguousarray(v) for k, v in out.items()}


def _models(maps: dict) -> tuple[str, ...]:
    """The models of ``maps`` in :data:`MODELS` order; every required one must be there."""
    missing = [m for m in REQUIRED if m not in maps]
    if missing:
        raise ValueError(f"a bake needs the {', '.join(missing)} maps")
    return tuple(m for m in MODELS if m in maps)


def _digest(header: dict, payload: bytes) -> str:
    rest = {k: v for k, v in header.items() if k != "checksum"}
    digest = hashlib.sha256(json.dumps(rest, sort_keys=True, separators=(",", ":")).encode())
    digest.update(payload)
    return digest.hexdigest()


def _shuffle(raw: bytes, itemsize: int) -> bytes:
    """Byte planes: all first bytes of the items, then all second bytes, ... (as Blosc).

    The high bytes of neighbouring half floats are alike, so zstd packs the planes
    about a quarter smaller than the interleaved bytes.
    """
    if itemsize == 1:
        return raw
    return np.frombuffer(raw, np.uint8).reshape(-1, itemsize).T.tobytes()


def _unshuffle(raw: bytes, itemsize: int) -> bytes:
    """The inverse of :func:`_shuffle`."""
    if itemsize == 1:
        return raw
    return np.frombuffer(raw, np.uint8).reshape(itemsize, -1).T.tobytes()


def save_pem(path: str | os.PathLike, bake: PemBake, level: int = 19) -> Path:
    """Write ``bake`` to ``path`` atomically (module docstring for the format).

    ``level`` is zstd's (19: small and slow, for files that are shipped; a full
    orbit's views, written as they are baked, take 3).

    Returns
    -------
    Path
        ``path``.
    """
    compressor = zstandard.ZstdCompressor(level=level)
    entries, frames, offset = [], [], 0
    for name, array in _arrays(bake).items():
        raw = array.astype(array.dtype.newbyteorder("<"), copy=False).tobytes()
        frame = compressor.compress(_shuffle(raw, array.dtype.itemsize))
        entries.append(
            {
                "name": name,
                "dtype": array.dtype.str.replace(">", "<").replace("=", "<"),
                "shape": list(array.shape),
                "offset": offset,
                "length": len(frame),
                "sha256": hashlib.sha256(raw).hexdigest(),
                "filter": "shuffle",
            }
        )
        frames.append(frame)
        offset += len(frame)
    payload = b"".join(frames)
    header = {
        "format": FORMAT,
        "version": VERSION,
        "scene": bake.scene,
        "view_space": bake.view_space,
        "views": bake.views,
        "parts": list(bake.parts),
        "em_size": bake.em_size,
        "levels": bake.levels,
        "models": {m: CHANNELS[m] for m in _models(bake.maps)},
        "parameters": bake.parameters,
        "mesh_checks": list(bake.mesh_checks),
        "arrays": entries,
    }
    header = json.loads(json.dumps(header))
    header["checksum"] = _digest(header, payload)
    text = json.dumps(header, sort_keys=True).encode()
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            f.write(_PREFIX.pack(MAGIC, VERSION, len(text)))
            f.write(text)
            f.write(payload)
    bake.header = header
    return Path(path)


def _version_one(path: Path) -> InputFileError:
    try:
        with np.load(path, allow_pickle=False) as data:
            header = json.loads(str(data["header"]))
        version = header.get("version")
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, AttributeError):
        return InputFileError(f"{path}: not a readable .pem bake (an unreadable zip archive)")
    return InputFileError(
        f"{path}: {FORMAT} version {version!r} (npz) is no longer read; this build reads "
        f"version {VERSION}: re-bake it with envstudio bake pem"
    )


def load_pem(path: str | os.PathLike) -> PemBake:
    """Read and verify a ``.pem`` file.

    Raises
    ------
    InputFileError
        One line naming the file and what is wrong: unreadable, not a ``.pem``, a
        version-1 file (re-bake), another version, truncated, checksum mismatch, or
        maps missing for views or parts.
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputFileError(f"{path}: not a readable .pem bake ({exc.strerror})") from None
    if data[:4] == b"PK\x03\x04":
        raise _version_one(path)
    if len(data) < _PREFIX.size or data[:8] != MAGIC:
        raise InputFileError(f"{path}: not a readable .pem bake (not an {FORMAT} file)")
    _, version, length = _PREFIX.unpack_from(data)
    if version != VERSION:
        raise InputFileError(
            f"{path}: {FORMAT} version {version}, this build reads {VERSION} (re-bake it)"
        )
    start = _PREFIX.size + length
    if len(data) < start:
        raise InputFileError(f"{path}: truncated (the header is cut short)")
    try:
        header = json.loads(data[_PREFIX.size : start].decode())
        entries = header["arrays"]
        need = max((e["offset"] + e["length"] for e in entries), default=0)
    except (ValueError, KeyError, TypeError, UnicodeDecodeError):
        raise InputFileError(f"{path}: not a readable .pem bake (bad header)") from None
    payload = data[start:]
    if len(payload) < need:
        raise InputFileError(
            f"{path}: truncated ({len(payload)} of {need} payload bytes; re-run the bake)"
        )
    if header.get("format") != FORMAT or header.get("version") != VERSION:
        raise InputFileError(f"{path}: not an {FORMAT} version {VERSION} header")
    if header.get("checksum") != _digest(header, payload[:need]) or len(payload) != need:
        raise InputFileError(f"{path}: checksum mismatch (the file is corrupt or was edited)")
    arrays = {}
    decompressor = zstandard.ZstdDecompressor()
    try:
        for e in entries:
            raw = decompressor.decompress(payload[e["offset"] : e["offset"] + e["length"]])
            if e.get("filter") == "shuffle":
                raw = _unshuffle(raw, np.dtype(e["dtype"]).itemsize)
            if hashlib.sha256(raw).hexdigest() != e["sha256"]:
                raise ValueError(e["name"])
            arrays[e["name"]] = np.frombuffer(raw, dtype=np.dtype(e["dtype"])).reshape(e["shape"])
    except (zstandard.ZstdError, ValueError, TypeError, KeyError):
        raise InputFileError(f"{path}: checksum mismatch (an array does not decode)") from None
    try:
        return _bake(path, header, arrays)
    except (KeyError, TypeError, ValueError) as exc:
        raise InputFileError(f"{path}: not a readable .pem bake (bad header: {exc})") from None


def _bake(path: Path, header: dict, arrays: dict) -> PemBake:
    space = header.get("view_space", {})
    parts = list(header.get("parts", []))
    levels = int(header.get("levels", 0))
    expected = len(space.get("azimuths", [])) * len(space.get("elevations", []))
    listed = header.get("models", {})
    models = REQUIRED + tuple(m for m in MODELS if m not in REQUIRED and m in listed)
    try:
        stored = {m: [arrays[f"maps/{m}/{k}"] for k in range(levels)] for m in models}
        hull = [arrays[f"hull/{p}"].astype(bool) for p in range(len(parts))]
        psnr = {m: arrays[f"psnr/{m}"].astype(np.float64) for m in models}
        playback = {
            n: arrays[f"playback_psnr/{n}"].astype(np.float64)
            for n in PLAYBACK
            if n != "ptm" or "ptm" in models
        }
        geometry = {n: arrays[n].astype(np.float64) for n in _GEOMETRY}
    except KeyError as exc:
        raise InputFileError(f"{path}: array {exc.args[0]} is missing") from None
    got = stored["distant"][0].shape[0] if levels and stored["distant"][0].ndim == 6 else 0
    if not (got == header.get("views") == expected == len(geometry["cameras"])):
        raise InputFileError(
            f"{path}: {got} views of maps for a view space of {expected} (views are missing)"
        )
    for m in models:
        for k, a in enumerate(stored[m]):
            n = header["em_size"] >> k
            if a.shape != (got, len(parts), 6, n, n, CHANNELS[m]):
                raise InputFileError(
                    f"{path}: maps/{m}/{k} is {a.shape}, expected "
                    f"{(got, len(parts), 6, n, n, CHANNELS[m])} (parts or levels are missing)"
                )
    return PemBake(
        scene=header["scene"],
        view_space=space,
        parts=parts,
        parameters=dict(header["parameters"]),
        maps={m: decode_levels(stored[m]) for m in models},
        hull=hull,
        mesh_checks=list(header.get("mesh_checks", [])),
        psnr=psnr,
        playback_psnr=playback,
        header=header,
        **geometry,
    )
