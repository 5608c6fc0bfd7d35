"""The atlas's grid: which cells it holds and the settings every cell shares."""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path

from envstudio.core.metrics import MIN_SIZE
from envstudio.errors import ParameterError
from envstudio.io.scene_file import shipped_environments
from envstudio.measure.compare import check_ssaa
from envstudio.measure.ground_truth import MAX_TIME_LIMIT_S

__all__ = [
    "DEFAULT_EXPONENTS",
    "DEFAULT_MESHES",
    "FORMAT_COPIES",
    "MAX_CAMERAS",
    "SHIPPED_MESHES",
    "AtlasGrid",
    "SceneCell",
    "default_envs",
]

#: Phong exponents of the default grid.
DEFAULT_EXPONENTS = (10.0, 100.0, 1000.0)
#: Reflector shapes of the default grid.
DEFAULT_MESHES = ("sphere", "knot")
#: Shipped maps that hold another shipped map in another file format (to read that format),
#: left out of the default grid: their cells equal the other's to the digits the atlas shows
#: (studies/atlas-full/README.md) and cost a ninth of its time.
FORMAT_COPIES = {"studio_rgbe.hdr": "studio"}
#: Shapes built in: a UV sphere, a (2, 3) torus knot (self-occluding), the shipped bunny.
SHIPPED_MESHES = ("sphere", "knot", "bunny")
#: Cameras a grid may spread in azimuth (one a degree).
MAX_CAMERAS = 360


def default_envs() -> tuple[str, ...]:
    """The default grid's maps: every shipped one but the :data:`FORMAT_COPIES`."""
    return tuple(name for name in shipped_environments() if name not in FORMAT_COPIES)


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

    Made only of values every cell can be measured with (finite, in range, the
    supersampling compare allows: ParameterError in one line otherwise); the
    files and names it lists are checked by :func:`.validate.check_grid`.
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
    reference: str = "exact"

    def __post_init__(self):
        if not self.methods:
            raise ParameterError("--methods: expected at least one method")
        for option, values in (("--exponents", self.exponents), ("--kd", self.kds)):
            if not values:
                raise ParameterError(f"{option}: expected at least one number")
            bad = [v for v in values if not math.isfinite(v)]
            if bad:
                raise ParameterError(f"{option} {bad[0]}: expected finite numbers")
        bad = [n for n in self.exponents if not n > 0]
        if bad:
            raise ParameterError(f"--exponents {bad[0]:g}: expected Phong exponents > 0")
        bad = [k for k in self.kds if not 0 <= k <= 1]
        if bad:
            raise ParameterError(f"--kd {bad[0]:g}: expected diffuse weights in [0, 1]")
        if not 1 <= self.cameras <= MAX_CAMERAS:
            raise ParameterError(f"--cameras {self.cameras}: expected 1..{MAX_CAMERAS}")
        if not 0 < self.time_limit <= MAX_TIME_LIMIT_S:
            raise ParameterError(
                f"--time-limit {self.time_limit}: expected a positive number of seconds "
                f"(at most {MAX_TIME_LIMIT_S:g})"
            )
        if min(self.size) < MIN_SIZE:
            raise ParameterError(
                f"--size {self.size[0]}x{self.size[1]}: expected at least {MIN_SIZE}x{MIN_SIZE}"
            )
        check_ssaa(self.ssaa, self.size, "--ssaa")

    @property
    def settings(self) -> dict:
        """What every cell shares: a folder holds the cells of one set of settings."""
        return {
            "size": list(self.size),
            "cameras": self.cameras,
            "time_limit": self.time_limit,
            "ssaa": self.ssaa,
            "params": list(self.params),
            "reference": self.reference,
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
