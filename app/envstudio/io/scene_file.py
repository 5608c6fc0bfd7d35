"""Scene files (TOML): environment, camera and objects.

Example::

    name = "studio"
    [environment]
    file = "hdr/studio.exr"          # relative to the scene file, then to assets/
    [camera]
    azimuth = 30.0                   # degrees
    elevation = 10.0
    distance = 3.0
    fov = 45.0
    [[object]]
    name = "bunny"
    mesh = "mesh/bunny.ply"          # or primitive = "sphere" | "box" | "room"
    role = "reflector"               # or "local"
    fit = 1.0                        # centre and scale into a sphere of this radius
    translation = [0.0, 0.0, 0.0]
    rotation = [0.0, 0.0, 0.0]       # XYZ Euler, degrees
    scale = 1.0
    components = [0, 1, 2]           # optional: keep these connected components
    subdivide = 2                    # optional: Loop subdivision steps (4x triangles each)
    color = [0.8, 0.2, 0.2]          # albedo of a local object
    [object.material]
    kd = [0.0, 0.0, 0.0]
    fresnel = 1.0
    phong_exponent = 200.0
    sharpness = 0.9                  # Banks s in [0, 1) (seed 004 §5.3)
    tangent_field = "axis"           # axis | direction | radial | uv (scene/tangents.py)
    tangent_axis = "y"               # x | y | z: the axis (axis, radial) or direction
    model = "banks"                  # optional: the reference's BRDF (phong | microfacet | banks)
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import tomllib

from envstudio.errors import InputFileError
from envstudio.io.images import read_environment
from envstudio.io.meshes import load_mesh
from envstudio.resources import asset_root
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene, Transform
from envstudio.scene.material import Material
from envstudio.scene.mesh import MeshData, loop_subdivided
from envstudio.scene.primitives import box, uv_sphere
from envstudio.scene.tangents import AXES, FIELDS, TangentField

#: The reference's BRDF models a material may name (methods/reference/method.py MODELS).
MODELS = ("phong", "microfacet", "banks")
#: The largest Banks sharpness the methods accept (their ``sharpness`` parameter).
SHARPNESS_MAX = 0.9999


def shipped_scenes() -> dict[str, Path]:
    """Scene name → file for the scenes in ``assets/scenes``."""
    return {p.stem: p for p in sorted((asset_root() / "scenes").glob("*.toml"))}


def shipped_environments() -> dict[str, Path]:
    """Environment name → file for the HDR maps in ``assets/hdr``."""
    folder = asset_root() / "hdr"
    return {
        p.stem if p.suffix == ".exr" else p.name: p
        for p in sorted(folder.glob("*.*"))
        if p.suffix in (".exr", ".hdr")
    }


def resolve_scene(name_or_path: str | os.PathLike) -> Path:
    """A shipped scene name (``studio``) or a path to a TOML file."""
    shipped = shipped_scenes()
    if str(name_or_path) in shipped:
        return shipped[str(name_or_path)]
    path = Path(name_or_path)
    if not path.is_file():
        raise InputFileError(
            f"{path}: no such scene file (shipped scenes: {', '.join(shipped) or 'none'})"
        )
    return path


def load_scene(name_or_path: str | os.PathLike) -> Scene:
    """Read a scene file (or a shipped scene by name) with its environment and meshes.

    Raises
    ------
    InputFileError
        Unreadable TOML, a missing key or a bad value, naming the file and key.
    """
    path = resolve_scene(name_or_path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputFileError(f"{path}: not a valid TOML scene ({exc})") from None
    reader = _SceneReader(path)
    env_spec = data.get("environment", {})
    if "file" not in env_spec:
        raise InputFileError(f'{path}: [environment] needs file = "..."')
    environment = Environment(
        read_environment(reader.find(env_spec["file"])), reader.find(env_spec["file"])
    )
    objects = data.get("object", [])
    if not objects:
        raise InputFileError(f"{path}: no [[object]] entries, expected at least one")
    nodes = [reader.node(i, spec) for i, spec in enumerate(objects)]
    cam = data.get("camera", {})
    camera = OrbitCamera(
        azimuth=reader.number(cam, "azimuth", 0.0, "camera"),
        elevation=reader.number(cam, "elevation", 0.0, "camera"),
        distance=reader.number(cam, "distance", 3.0, "camera"),
        target=reader.vector(cam, "target", (0.0, 0.0, 0.0), "camera"),
        fov_y=reader.number(cam, "fov", 45.0, "camera"),
    )
    return Scene(environment, nodes, camera, data.get("name", path.stem))


def scene_from_files(env_path: str | os.PathLike, mesh_path: str | os.PathLike | None) -> Scene:
    """A one-reflector scene: ``mesh_path`` (or a sphere) under the environment ``env_path``."""
    env_path = Path(env_path)
    mesh = load_mesh(mesh_path).fitted(1.0) if mesh_path else uv_sphere(1.0)
    return Scene(
        Environment(read_environment(env_path), env_path),
        [Node(mesh.name, mesh)],
        OrbitCamera(distance=3.2),
        mesh.name,
    )


class _SceneReader:
    def __init__(self, path: Path):
        self.path = path

    def find(self, name: str) -> Path:
        for base in (self.path.parent, asset_root()):
            candidate = base / name
            if candidate.is_file():
                return candidate
        raise InputFileError(f"{self.path}: referenced file {name!r} not found")

    def number(self, spec: dict, key: str, default: float, where: str) -> float:
        value = spec.get(key, default)
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            raise InputFileError(f"{self.path}: {where}.{key} = {value!r}, expected a number")
        return float(value)

    def vector(self, spec: dict, key: str, default: tuple, where: str) -> tuple:
        value = spec.get(key, default)
        ok = isinstance(value, (list, tuple)) and len(value) == 3
        if not ok or not all(isinstance(v, (int, float)) for v in value):
            raise InputFileError(f"{self.path}: {where}.{key} = {value!r}, expected [x, y, z]")
        return tuple(float(v) for v in value)

    def choice(
        self, spec: dict, key: str, default: str | None, choices: tuple[str, ...], where: str
    ) -> str | None:
        """``spec[key]`` (or ``default`` when absent), one of ``choices``, else a one-line error."""
        value = spec.get(key, default)
        if value is not default and value not in choices:
            raise InputFileError(
                f"{self.path}: {where}.{key} = {value!r}, expected one of {', '.join(choices)}"
            )
        return value

    def sharpness(self, spec: dict, where: str) -> float:
        """The Banks sharpness s ∈ [0, :data:`SHARPNESS_MAX`] (default 0.9), else an error."""
        value = self.number(spec, "sharpness", 0.9, where)
        if not 0.0 <= value <= SHARPNESS_MAX:
            raise InputFileError(
                f"{self.path}: {where}.sharpness = {value!r}, expected a number in [0, 1) "
                f"(at most {SHARPNESS_MAX})"
            )
        return value

    def node(self, index: int, spec: dict[str, Any]) -> Node:
        where = f"object[{index}]"
        name = str(spec.get("name", f"object{index}"))
        mesh = self.mesh(spec, where)
        if "fit" in spec:
            mesh = mesh.fitted(self.number(spec, "fit", 1.0, where))
        role = spec.get("role", "reflector")
        if role not in ("reflector", "local"):
            raise InputFileError(
                f"{self.path}: {where}.role = {role!r}, expected reflector or local"
            )
        mat = spec.get("material", {})
        kd = mat.get("kd", (0.0, 0.0, 0.0))
        kd = (float(kd),) * 3 if isinstance(kd, (int, float)) else self.vector(mat, "kd", kd, where)
        material = Material(
            kd=kd,
            fresnel=self.number(mat, "fresnel", 1.0, f"{where}.material"),
            phong_exponent=self.number(mat, "phong_exponent", 200.0, f"{where}.material"),
            sharpness=self.sharpness(mat, f"{where}.material"),
            tangent_field=TangentField(
                self.choice(mat, "tangent_field", "axis", FIELDS, f"{where}.material"),
                self.choice(mat, "tangent_axis", "y", tuple(AXES), f"{where}.material"),
            ),
            model=self.choice(mat, "model", None, MODELS, f"{where}.material"),
        )
        transform = Transform(
            self.vector(spec, "translation", (0.0, 0.0, 0.0), where),
            self.vector(spec, "rotation", (0.0, 0.0, 0.0), where),
            self.number(spec, "scale", 1.0, where),
        )
        color = self.vector(spec, "color", (0.8, 0.8, 0.8), where)
        return Node(name, mesh, material, transform, role, color)

    def mesh(self, spec: dict[str, Any], where: str) -> MeshData:
        if "mesh" in spec:
            steps = spec.get("subdivide", 0)
            if not isinstance(steps, int) or isinstance(steps, bool) or not 0 <= steps <= 4:
                raise InputFileError(
                    f"{self.path}: {where}.subdivide = {steps!r}, expected a whole number in 0..4"
                )
            mesh = load_mesh(self.find(spec["mesh"]), spec.get("components"))
            return loop_subdivided(mesh, steps) if steps else mesh
        primitive = spec.get("primitive")
        size = self.number(spec, "size", 1.0, where)
        makers = {
            "sphere": lambda: uv_sphere(size / 2),
            "box": lambda: box(size),
            "room": lambda: box(size, inward=True),
        }
        if primitive not in makers:
            raise InputFileError(
                f'{self.path}: {where} needs mesh = "file" or primitive = sphere|box|room'
            )
        return makers[primitive]()
