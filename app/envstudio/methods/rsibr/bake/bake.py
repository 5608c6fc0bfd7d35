"""The radiance sphere maps of seed 002 (§2, §3.1, §4): bake, save, load, cache.

A bake is one map per geodesic view direction v_j (the 12 icosahedron vertices,
or the 42 of its subdivision), each in the frame T_j of a camera looking from
v_j (methods.rsibr.warp.view_frame), with the faces that §4's
FindSubtendedTriangle searches: the viewer reads the views from the file, so it
is "decoupled from any specific choice of sphere map sampling view directions".

File format (``.rsibr``): a NumPy ``.npz`` (uncompressed zip) holding

=========== ======================= ==============================================
``header``  0-d str                 JSON: ``format`` ("envstudio-rsibr"),
                                    ``version`` (1), ``brdf``, ``warp``,
                                    ``parameters`` (name → value), ``size`` (n),
                                    ``views`` (V), ``samples``, ``device``,
                                    ``environment`` (SHA-256 of the environment's
                                    pixels), ``checksum`` (below)
``maps``    (V, n, n, 3) float32    linear radiance, core.spheremap layout
                                    (row 0 = t = 0), map j in frame T_j
``views``   (V, 3) float64          unit v_j, world space (toward the camera)
``frames``  (V, 3, 3) float64       T_j, columns x, y, z (world = T_j @ local)
``faces``   (F, 3) int32            counter-clockwise triangles of the views
=========== ======================= ==============================================

``checksum`` is the SHA-256 of the bytes of ``maps``, ``views``, ``frames`` and
``faces`` in that order, then the header without its checksum. Files are written
atomically (io.atomic); :func:`load_bake` refuses, with one line, a file that is
not a bake, whose checksum does not match, whose views lack a map or whose size
is not the one asked for.
"""

from __future__ import annotations

import hashlib
import json
import os
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from envstudio.core.icosahedron import icosahedron, subdivide
from envstudio.errors import InputFileError, ParameterError
from envstudio.io.atomic import atomic_path
from envstudio.io.cache_folder import cache_folder
from envstudio.methods.rsibr.bake.brdfs import brdf
from envstudio.methods.rsibr.bake.cpu import bake_view_cpu
from envstudio.methods.rsibr.warp import view_frame
from envstudio.resources import shader_root

__all__ = [
    "FORMAT",
    "VERSION",
    "RsibrBake",
    "bake_cpu",
    "cache_dir",
    "cache_key",
    "environment_key",
    "geodesic_views",
    "load_bake",
    "save_bake",
]

FORMAT = "envstudio-rsibr"
VERSION = 1


@dataclass
class RsibrBake:
    """Radiance sphere maps and what they were made from (module docstring).

    Attributes
    ----------
    maps : (V, n, n, 3) float32
        Linear radiance per view.
    views : (V, 3) float64
        Unit view directions v_j.
    frames : (V, 3, 3) float64
        Camera frames T_j.
    faces : (F, 3) int32
        Triangles of the views.
    brdf : str
        BRDF name (bake.rsibr.brdfs).
    parameters : dict
        Its parameter values.
    samples : int
        Importance samples per lobe (GPU) or 0 (CPU quadrature).
    device : str
        ``gpu`` or ``cpu``.
    environment : str
        :func:`environment_key` of the lighting.
    """

    maps: npt.NDArray[np.float32]
    views: npt.NDArray[np.float64]
    frames: npt.NDArray[np.float64]
    faces: npt.NDArray[np.int32]
    brdf: str
    parameters: dict[str, float]
    samples: int
    device: str
    environment: str
    header: dict = field(default_factory=dict)

    @property
    def size(self) -> int:
        """Map edge n in texels."""
        return int(self.maps.shape[1])

    @property
    def warp(self) -> str:
        """The warp of the BRDF (§3.3)."""
        return brdf(self.brdf).warp


def geodesic_views(count: int = 12) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int32]]:
    """(views (V, 3), faces (F, 3)): the icosahedron (12) or its subdivision (42)."""
    vertices, faces = icosahedron()
    if count == 42:
        return subdivide(vertices, faces)
    if count != 12:
        raise ParameterError(f"--views {count}: expected 12 (icosahedron) or 42 (subdivided)")
    return vertices, faces


def environment_key(pixels: npt.ArrayLike) -> str:
    """SHA-256 (hex) of an environment's float32 pixels and shape."""
    array = np.ascontiguousarray(pixels, dtype=np.float32)
    digest = hashlib.sha256(repr(array.shape).encode())
    digest.update(array.tobytes())
    return digest.hexdigest()


def cache_dir() -> Path:
    """Bakes' cache folder: ``rsibr`` in envstudio's (:func:`.cache_folder`)."""
    return cache_folder("rsibr")


def cache_key(
    environment: str, name: str, values: dict[str, float], size: int, views: int, samples: int
) -> str:
    """Cache file name of a bake (the shader's text is part of it: a change rebakes)."""
    payload = json.dumps(
        [environment, name, sorted(values.items()), size, views, samples], sort_keys=True
    )
    digest = hashlib.sha256(payload.encode())
    digest.update((shader_root() / "rsibr" / "bake.glsl").read_text(encoding="utf-8").encode())
    return f"{digest.hexdigest()[:32]}.rsibr"


def bake_cpu(
    environment: npt.ArrayLike,
    name: str,
    values: dict[str, object] | None = None,
    size: int = 64,
    views: int = 12,
    progress: Callable[[int], None] | None = None,
) -> RsibrBake:
    """Every view's map on the CPU (bake.rsibr.cpu).

    Parameters
    ----------
    environment : (h, 2h, 3) float
        Lat-long radiance.
    name, values
        BRDF and its parameters (validated; defaults for the rest).
    size
        Map edge n.
    views
        12 or 42 (:func:`geodesic_views`).
    progress
        Called with texels finished.
    """
    spec = brdf(name)
    params = spec.values(values)
    vertices, faces = geodesic_views(views)
    frames = np.stack([view_frame(v) for v in vertices])
    maps = np.stack([bake_view_cpu(environment, name, params, t, size, progress) for t in frames])
    return RsibrBake(
        maps, vertices, frames, faces, name, params, 0, "cpu", environment_key(environment)
    )


def save_bake(path: str | os.PathLike, bake: RsibrBake) -> Path:
    """Write ``bake`` to ``path`` atomically in the format of the module docstring."""
    header = {
        "format": FORMAT,
        "version": VERSION,
        "brdf": bake.brdf,
        "warp": bake.warp,
        "parameters": bake.parameters,
        "size": bake.size,
        "views": len(bake.views),
        "samples": int(bake.samples),
        "device": bake.device,
        "environment": bake.environment,
    }
    arrays = _arrays(bake)
    header["checksum"] = _checksum(arrays, header)
    with atomic_path(path, need=sum(a.nbytes for a in arrays.values())) as tmp:
        with open(tmp, "wb") as f:
            np.savez(f, header=np.array(json.dumps(header, sort_keys=True)), **arrays)
    return Path(path)


def load_bake(path: str | os.PathLike, size: int | None = None) -> RsibrBake:
    """Read and check a bake file.

    Parameters
    ----------
    path
        A ``.rsibr`` file.
    size
        Map edge the caller needs; None accepts any.

    Raises
    ------
    InputFileError
        One line naming the file and what is wrong: unreadable, not a bake, checksum
        mismatch, missing views, or another size.
    """
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            header = json.loads(str(data["header"]))
            arrays = {k: np.asarray(data[k]) for k in ("maps", "views", "frames", "faces")}
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as exc:
        raise InputFileError(f"{path}: not a readable .rsibr bake ({exc})") from None
    if header.get("format") != FORMAT or header.get("version") != VERSION:
        raise InputFileError(f"{path}: not an {FORMAT} version {VERSION} file")
    if header.get("checksum") != _checksum(arrays, header):
        raise InputFileError(f"{path}: checksum mismatch (the file is corrupt or was edited)")
    maps, views = arrays["maps"], arrays["views"]
    if maps.ndim != 4 or maps.shape[0] != len(views) or len(views) != header.get("views"):
        raise InputFileError(
            f"{path}: {maps.shape[0] if maps.ndim == 4 else 0} maps for "
            f"{header.get('views')} views (views are missing)"
        )
    if arrays["faces"].size == 0 or arrays["faces"].max() >= len(views):
        raise InputFileError(f"{path}: faces refer to views that are missing")
    if size is not None and maps.shape[1] != size:
        raise InputFileError(f"{path}: maps are {maps.shape[1]}², expected {size}²")
    return RsibrBake(
        maps.astype(np.float32),
        views.astype(np.float64),
        arrays["frames"].astype(np.float64),
        arrays["faces"].astype(np.int32),
        header["brdf"],
        dict(header["parameters"]),
        int(header["samples"]),
        header["device"],
        header["environment"],
        header,
    )


def _arrays(bake: RsibrBake) -> dict[str, np.ndarray]:
    return {
        "maps": np.ascontiguousarray(bake.maps, dtype=np.float32),
        "views": np.ascontiguousarray(bake.views, dtype=np.float64),
        "frames": np.ascontiguousarray(bake.frames, dtype=np.float64),
        "faces": np.ascontiguousarray(bake.faces, dtype=np.int32),
    }


def _checksum(arrays: dict[str, np.ndarray], header: dict) -> str:
    digest = hashlib.sha256()
    for name in ("maps", "views", "frames", "faces"):
        digest.update(np.ascontiguousarray(arrays[name]).tobytes())
    rest = {k: v for k, v in header.items() if k != "checksum"}
    digest.update(json.dumps(rest, sort_keys=True).encode())
    return digest.hexdigest()
