"""Environment at infinity: a lat-long radiance map (plain data)."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt


@dataclass
class Environment:
    """Distant lighting as a lat-long radiance map.

    Attributes
    ----------
    radiance : (h, 2h, 3) float32
        Linear RGB radiance, row 0 looking up (+Y); lat-long convention of DESIGN.md.
    source : Path or None
        File the map was read from (None for procedural maps).
    """

    radiance: npt.NDArray[np.float32]
    source: Path | None = None

    @property
    def name(self) -> str:
        """Short name for the UI."""
        return self.source.stem if self.source else "procedural"

    def checksum(self) -> str:
        """SHA-256 (hex) of the radiance's float32 pixels and shape: which map this is."""
        pixels = np.ascontiguousarray(self.radiance, dtype=np.float32)
        digest = hashlib.sha256(repr(pixels.shape).encode())
        digest.update(pixels.tobytes())
        return digest.hexdigest()

    @classmethod
    def constant(cls, rgb: npt.ArrayLike, height: int = 8) -> Environment:
        """A uniform environment of radiance ``rgb`` (3,)."""
        img = np.empty((height, 2 * height, 3), dtype=np.float32)
        img[:] = np.asarray(rgb, dtype=np.float32)
        return cls(img)
