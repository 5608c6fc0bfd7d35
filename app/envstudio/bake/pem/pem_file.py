"""The ``.pem`` file: one PEM bake's per-view inferred environment maps (seed 003 §4).

Seed 003 §3 ("System Overview") bakes, for every sample of the parameter space
(views), per reflector part, the environment maps the playback renders with;
this file holds the distant layer's box EMs inferred by
:func:`envstudio.bake.pem.infer.infer_distant` (finest MIP level), with the EM
geometries and origins (§4, "EM Representations", "Layered EMs").

File format (``.pem``, version 1): a NumPy ``.npz`` (zip, deflate) holding

============== ========================== ===========================================
``header``     0-d str                    JSON: ``format`` ("envstudio-pem"),
                                          ``version`` (1), ``scene`` (name),
                                          ``view_space`` (ViewSpace.describe():
                                          kind, azimuths, elevations, distance,
                                          target, fov_y), ``views`` (V),
                                          ``parts`` (the P part names),
                                          ``parameters`` (size R, samples,
                                          em_size n, smoothness λ, seed, bounces,
                                          layer, geometry), ``checksum`` (below)
``distant``    (V, P, 6, n, n, 3) float32 the distant EM per view and part, linear
                                          radiance, OpenGL cube-face order
                                          (core/cubemap.py)
``seen``       (V, P, 6, n, n) uint8      1 where a texel contributes to a pixel
``psnr``       (V, P) float64             A x against the traced layer, dB
``iterations`` (V, P, 3) int32            CG iterations per channel
``cameras``    (V, 2) float64             azimuth, elevation of each view, degrees
``box``        (2, 3) float64             the distant box map: lo, hi corners
``origins``    (P, 3) float64             EM origin per part (area-weighted
                                          mean of its triangle centroids)
``ellipsoids`` (P, 2, 3) float64          the local layer's minimum-volume
                                          ellipsoid per part: centre, radii
============== ========================== ===========================================

Views are in ViewSpace.cameras() order (elevation-major). ``checksum`` is the
SHA-256 of the bytes of the arrays in the order of the table, then the JSON of
the header without its checksum (sorted keys). The maps are float32, not the
issue's zstd half floats (PyPI ``zstandard`` is not a dependency here), and
without MIP residuals (levels are not inferred yet). Files are written
atomically (io.atomic); :func:`load_pem` refuses with one line a file that is
not a ``.pem``, of another version, whose checksum does not match or whose
views are missing.
"""

from __future__ import annotations

import hashlib
import json
import os
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from envstudio.errors import InputFileError
from envstudio.io.atomic import atomic_path

__all__ = ["ARRAYS", "FORMAT", "VERSION", "PemBake", "load_pem", "save_pem"]

FORMAT = "envstudio-pem"
VERSION = 1

#: Array names in checksum order, with their stored dtypes.
ARRAYS = {
    "distant": np.float32,
    "seen": np.uint8,
    "psnr": np.float64,
    "iterations": np.int32,
    "cameras": np.float64,
    "box": np.float64,
    "origins": np.float64,
    "ellipsoids": np.float64,
}


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
        Bake parameters (size, samples, em_size, smoothness, seed, bounces, layer,
        geometry).
    distant : (V, P, 6, n, n, 3) float32
    seen : (V, P, 6, n, n) uint8
    psnr : (V, P) float64
    iterations : (V, P, 3) int32
    cameras : (V, 2) float64
    box : (2, 3) float64
    origins : (P, 3) float64
    ellipsoids : (P, 2, 3) float64
    header : dict
        The header as read (empty for a bake not yet saved).
    """

    scene: str
    view_space: dict
    parts: list[str]
    parameters: dict
    distant: npt.NDArray[np.float32]
    seen: npt.NDArray[np.uint8]
    psnr: npt.NDArray[np.float64]
    iterations: npt.NDArray[np.int32]
    cameras: npt.NDArray[np.float64]
    box: npt.NDArray[np.float64]
    origins: npt.NDArray[np.float64]
    ellipsoids: npt.NDArray[np.float64]
    header: dict = field(default_factory=dict)

    @property
    def views(self) -> int:
        """V, the number of views."""
        return int(self.distant.shape[0])

    @property
    def em_size(self) -> int:
        """n, the cube face edge in texels."""
        return int(self.distant.shape[3])

    def arrays(self) -> dict[str, np.ndarray]:
        """The stored arrays, contiguous, in their file dtypes (checksum order)."""
        return {k: np.ascontiguousarray(getattr(self, k), dtype=t) for k, t in ARRAYS.items()}


def _header(bake: PemBake) -> dict:
    return {
        "format": FORMAT,
        "version": VERSION,
        "scene": bake.scene,
        "view_space": bake.view_space,
        "views": bake.views,
        "parts": list(bake.parts),
        "parameters": bake.parameters,
    }


def _checksum(arrays: dict[str, np.ndarray], header: dict) -> str:
    digest = hashlib.sha256()
    for name in ARRAYS:
        digest.update(np.ascontiguousarray(arrays[name]).tobytes())
    rest = {k: v for k, v in header.items() if k != "checksum"}
    digest.update(json.dumps(rest, sort_keys=True).encode())
    return digest.hexdigest()


def save_pem(path: str | os.PathLike, bake: PemBake) -> Path:
    """Write ``bake`` to ``path`` atomically (module docstring for the format).

    Returns
    -------
    Path
        ``path``.
    """
    arrays = bake.arrays()
    header = _header(bake)
    header["checksum"] = _checksum(arrays, header)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            np.savez_compressed(f, header=np.array(json.dumps(header, sort_keys=True)), **arrays)
    bake.header = header
    return Path(path)


def load_pem(path: str | os.PathLike) -> PemBake:
    """Read and verify a ``.pem`` file.

    Raises
    ------
    InputFileError
        One line naming the file and what is wrong: unreadable or truncated, not a
        ``.pem``, another version, checksum mismatch, or views missing.
    """
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            header = json.loads(str(data["header"]))
            arrays = {k: np.asarray(data[k]) for k in ARRAYS}
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputFileError(f"{path}: not a readable .pem bake ({reason})") from None
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise InputFileError(f"{path}: not an {FORMAT} file")
    if header.get("version") != VERSION:
        raise InputFileError(
            f"{path}: {FORMAT} version {header.get('version')!r}, this build reads {VERSION}"
        )
    if header.get("checksum") != _checksum(arrays, header):
        raise InputFileError(f"{path}: checksum mismatch (the file is corrupt or was edited)")
    distant = arrays["distant"]
    space = header.get("view_space", {})
    expected = len(space.get("azimuths", [])) * len(space.get("elevations", []))
    got = distant.shape[0] if distant.ndim == 6 else 0
    if not (got == header.get("views") == expected == len(arrays["cameras"])):
        raise InputFileError(
            f"{path}: {got} views of maps for a view space of {expected} (views are missing)"
        )
    if distant.shape[1] != len(header.get("parts", [])):
        raise InputFileError(
            f"{path}: maps for {distant.shape[1]} parts, header names "
            f"{len(header.get('parts', []))}"
        )
    return PemBake(
        header["scene"],
        space,
        list(header["parts"]),
        dict(header["parameters"]),
        header=header,
        **arrays,
    )
