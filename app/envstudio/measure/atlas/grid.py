"""The atlas's grid: which cells it holds and the settings every cell shares."""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass
from pathlib import Path

from envstudio.errors import ParameterError

__all__ = ["DEFAULT_EXPONENTS", "DEFAULT_MESHES", "SHIPPED_MESHES", "AtlasGrid", "SceneCell"]

#: Phong exponents of the default grid.
DEFAULT_EXPONENTS = (10.0, 100.0, 1000.0)
#: Reflector shapes of the default grid.
DEFAULT_MESHES = ("sphere", "knot")
#: Shapes built in: a UV sphere, a (2, 3) torus knot (self-occluding), the shipped bunny.
SHIPPED_MESHES = ("sphere", "knot", "bunny")


@dataclass(frozen=True)
class SceneCell:
    """Everything of a cell but the method: one ``compare`` run.

    Attributes
    ----------
    env : str
        Shipped environment name or file path.
    mesh : str
        ``sphere``, ``knot``, ``bunny`` or a mesh file path.
    exponent : float
        Phong exponent N every method is matched to.
    kd : float
        Diffuse weight.
    camera : int
        Camera index k of K: the scene camera turned by 360° k / K in azimuth.
    """

    env: str
    mesh: str
    exponent: float
    kd: float
    camera: int

    @property
    def key(self) -> str:
        """A file-name-safe name of the cell, unique in a grid."""
        text = json.dumps(asdict(self), sort_keys=True)
        stem = f"{Path(self.env).stem}-{Path(self.mesh).stem}-N{self.exponent:g}-kd{self.kd:g}"
        return f"{stem}-c{self.camera}-{hashlib.sha1(text.encode()).hexdigest()[:8]}"


@dataclass(frozen=True)
class AtlasGrid:
    """The lists that span the grid and the settings all its cells share.

    ``settings`` (size, cameras, time limit, supersampling, the ``--param``
    assignments every method of every cell gets) must match for two
    runs to share a folder; the lists may grow, and only new cells are measured.
    """

    methods: tuple[str, ...]
    envs: tuple[str, ...]
    meshes: tuple[str, ...]
    exponents: tuple[float, ...]
    kds: tuple[float, ...]
    size: tuple[int, int]
    cameras: int
    time_limit: float
    ssaa: int
    params: tuple[str, ...] = ()

    def __post_init__(self):
        if not self.methods:
            raise ParameterError("--methods: expected at least one method")
        bad = [n for n in self.exponents if not n > 0]
        if bad:
            raise ParameterError(f"--exponents {bad[0]:g}: expected Phong exponents > 0")
        bad = [k for k in self.kds if not 0 <= k <= 1]
        if bad:
            raise ParameterError(f"--kd {bad[0]:g}: expected diffuse weights in [0, 1]")
        if self.cameras < 1:
            raise ParameterError(f"--cameras {self.cameras}: expected at least 1")

    @property
    def settings(self) -> dict:
        """What every cell shares: a folder holds the cells of one set of settings."""
        return {
            "size": list(self.size),
            "cameras": self.cameras,
            "time_limit": self.time_limit,
            "ssaa": self.ssaa,
            "params": list(self.params),
        }

    def scene_cells(self) -> list[SceneCell]:
        """Every scene of the grid, environments outermost."""
        return [
            SceneCell(env, mesh, float(n), float(kd), k)
            for env in self.envs
            for mesh in self.meshes
            for n in self.exponents
            for kd in self.kds
            for k in range(self.cameras)
        ]

    def to_json(self) -> dict:
        return {
            "methods": list(self.methods),
            "envs": list(self.envs),
            "meshes": list(self.meshes),
            "exponents": list(self.exponents),
            "kds": list(self.kds),
            **self.settings,
        }
