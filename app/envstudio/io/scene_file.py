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
    [proxy]                          # optional: the volume parallax-corrected cube maps
    shape = "box"                    # intersect (methods/parallax); or "sphere" with
    min = [-4.0, -0.5, -4.0]         # centre = [x, y, z] and radius = R
    max = [4.0, 7.5, 4.0]
    probe = [0.0, 0.4, 0.0]          # optional capture point (default: the reflectors' centre)
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
    kd = [0.0, 0.0, 0.0]             # or one number (grey)
    fresnel = 1.0                    # f_λ: one number, [r, g, b] or a preset ("gold", ...)
    phong_exponent = 200.0
    sharpness = 0.9                  # Banks s in [0, 1) (seed 004 §5.3)
    tangent_field = "axis"           # axis | direction | radial | uv (scene/tangents.py)
    tangent_axis = "y"               # x | y | z: the axis (axis, radial) or direction
    model = "banks"                  # optional: the reference's BRDF (phong | microfacet | banks)

The file is checked against :class:`SceneSpec` (msgspec) before anything is
loaded: a key of the wrong type, a value out of range (fov outside (0, 180), a
distance, scale, fit or size ≤ 0, NaN or Inf anywhere) or an unknown key (with a
"did you mean") is one line naming the file, the key path and what was expected.
"""

from __future__ import annotations

import difflib
import os
import re
import typing
from pathlib import Path
from typing import Annotated, Literal

import msgspec
import tomllib

from envstudio.core.presets import FRESNEL_RGB
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
from envstudio.scene.proxy import BoxProxy, Proxy, SphereProxy
from envstudio.scene.tangents import AXES, FIELDS, TangentField

#: The reference's BRDF models a material may name (methods/reference/method.py MODELS).
MODELS = ("phong", "microfacet", "banks")
#: The largest Banks sharpness the methods accept (their ``sharpness`` parameter).
SHARPNESS_MAX = 0.9999
_LIMIT = 1e30  # coordinates past this are out of range (and NaN and Inf are refused)

Finite = Annotated[float, msgspec.Meta(ge=-_LIMIT, le=_LIMIT)]
Positive = Annotated[float, msgspec.Meta(gt=0.0, le=_LIMIT)]
Unit = Annotated[float, msgspec.Meta(ge=0.0, le=1.0)]
Vector = tuple[Finite, Finite, Finite]
Colour = tuple[Unit, Unit, Unit]
# kd's union names its three components as a list: msgspec 0.23 crashes at exit with a
# union of an Annotated float and a tuple of them.
ColourList = Annotated[list[Unit], msgspec.Meta(min_length=3, max_length=3)]
PresetName = Annotated[str, msgspec.Meta(description="an f_λ preset: " + ", ".join(FRESNEL_RGB))]
Sharpness = Annotated[
    float,
    msgspec.Meta(
        ge=0.0, le=SHARPNESS_MAX, description=f"a number in [0, 1) (at most {SHARPNESS_MAX})"
    ),
]


class EnvironmentSpec(msgspec.Struct, forbid_unknown_fields=True):
    """``[environment]``: the lat-long map, relative to the scene file, then to assets/."""

    file: str


class CameraSpec(msgspec.Struct, forbid_unknown_fields=True):
    """``[camera]``: orbit angles in degrees, distance in scene units, vertical fov."""

    azimuth: Finite = 0.0
    elevation: Finite = 0.0
    distance: Positive = 3.0
    target: Vector = (0.0, 0.0, 0.0)
    fov: Annotated[float, msgspec.Meta(gt=0.0, lt=180.0)] = 45.0


class MaterialSpec(msgspec.Struct, forbid_unknown_fields=True):
    """``[object.material]``: eq. 8's k_d and f_λ, Phong N, Banks keys, the reference's model."""

    kd: Unit | ColourList = 0.0
    fresnel: Unit | ColourList | PresetName = 1.0  # a name: core/presets.py's f_λ
    phong_exponent: Positive = 200.0
    sharpness: Sharpness = 0.9
    tangent_field: Literal[FIELDS] = "axis"  # type: ignore[valid-type]
    tangent_axis: Literal[tuple(AXES)] = "y"  # type: ignore[valid-type]
    model: Literal[MODELS] | None = None  # type: ignore[valid-type]


class ObjectSpec(msgspec.Struct, forbid_unknown_fields=True):
    """``[[object]]``: a mesh file or a primitive, its role, placement and material."""

    name: str | None = None
    mesh: str | None = None
    primitive: Literal["sphere", "box", "room"] | None = None
    size: Positive = 1.0
    role: Literal["reflector", "local"] = "reflector"
    fit: Positive | None = None
    translation: Vector = (0.0, 0.0, 0.0)
    rotation: Vector = (0.0, 0.0, 0.0)
    scale: Positive = 1.0
    components: list[Annotated[int, msgspec.Meta(ge=0)]] | None = None
    subdivide: Annotated[int, msgspec.Meta(ge=0, le=4)] = 0
    color: Colour = (0.8, 0.8, 0.8)
    material: MaterialSpec = msgspec.field(default_factory=MaterialSpec)


class ProxySpec(msgspec.Struct, forbid_unknown_fields=True):
    """``[proxy]``: a box (``min``, ``max``) or a sphere (``centre``, ``radius``), world space.

    ``probe`` is the point the cube map is captured from (default: the reflectors'
    centre); it must lie inside the proxy (:func:`_proxy`).
    """

    shape: Literal["box", "sphere"]
    min: Vector | None = None
    max: Vector | None = None
    centre: Vector | None = None
    radius: Positive | None = None
    probe: Vector | None = None


class SceneSpec(msgspec.Struct, forbid_unknown_fields=True):
    """A scene file's top level."""

    environment: EnvironmentSpec
    object: Annotated[list[ObjectSpec], msgspec.Meta(min_length=1)]
    name: str | None = None
    camera: CameraSpec = msgspec.field(default_factory=CameraSpec)
    proxy: ProxySpec | None = None


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


def load_scene(name_or_path: str | os.PathLike, max_env_width: int | None = None) -> Scene:
    """Read a scene file (or a shipped scene by name) with its environment and meshes.

    The environment is box-filtered to at most ``max_env_width`` texels wide as it is
    read (None: as it is).

    Raises
    ------
    InputFileError
        Unreadable TOML, or a key missing, unknown, of the wrong type or out of
        range (:class:`SceneSpec`), naming the file and the key path.
    """
    path = resolve_scene(name_or_path)
    spec = read_scene_spec(path)
    reader = _SceneReader(path)
    env_file = reader.find(spec.environment.file)
    environment = Environment(read_environment(env_file, max_env_width), env_file)
    nodes = [reader.node(i, obj) for i, obj in enumerate(spec.object)]
    cam = spec.camera
    camera = OrbitCamera(
        azimuth=cam.azimuth,
        elevation=cam.elevation,
        distance=cam.distance,
        target=cam.target,
        fov_y=cam.fov,
    )
    scene = Scene(environment, nodes, camera, spec.name or path.stem, source=str(path.resolve()))
    if spec.proxy is not None:
        scene.proxy = _proxy(path, spec.proxy, scene)
    return scene


def _proxy(path: Path, spec: ProxySpec, scene: Scene) -> Proxy:
    """The scene's proxy volume, with the keys its shape needs and the probe inside it."""
    keys = {"box": ("min", "max"), "sphere": ("centre", "radius")}
    needed = keys[spec.shape]
    for key in needed:
        if getattr(spec, key) is None:
            raise InputFileError(
                f"{path}: proxy.{key} is missing (a {spec.shape} needs {needed[0]} and {needed[1]})"
            )
    for shape, others in keys.items():
        extra = [key for key in others if shape != spec.shape and getattr(spec, key) is not None]
        if extra:
            raise InputFileError(
                f"{path}: proxy.{extra[0]} belongs to shape = {shape!r}, not {spec.shape!r}"
            )
    if spec.shape == "box":
        if not all(lo < hi for lo, hi in zip(spec.min, spec.max, strict=True)):
            raise InputFileError(
                f"{path}: proxy.min = {list(spec.min)}, expected below proxy.max = "
                f"{list(spec.max)} on every axis"
            )
        proxy = BoxProxy(spec.min, spec.max, spec.probe)
    else:
        proxy = SphereProxy(spec.centre, spec.radius, spec.probe)
    probe = scene.reflector_centre() if spec.probe is None else spec.probe
    if not proxy.contains(probe):
        which = "proxy.probe" if spec.probe is not None else "the reflectors' centre (the probe)"
        raise InputFileError(
            f"{path}: the proxy {proxy.describe()} does not contain {which} "
            f"[{', '.join(f'{float(v):g}' for v in probe)}]; expected the probe inside it "
            "(declare proxy.probe = [x, y, z] inside, or enlarge the proxy)"
        )
    return proxy


def read_scene_spec(path: Path) -> SceneSpec:
    """The scene file at ``path``, parsed and checked against :class:`SceneSpec`."""
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputFileError(f"{path}: not a valid TOML scene ({exc})") from None
    try:
        return msgspec.convert(data, SceneSpec)
    except msgspec.ValidationError as exc:
        raise InputFileError(f"{path}: {_explain(str(exc), data)}") from None


_AT = re.compile(r"^(?P<what>.*?)(?: - at `\$(?P<where>[^`]*)`)?$")
_STEP = re.compile(r"\.(\w+)|\[(\d+)\]")


def _explain(message: str, data: dict) -> str:
    """msgspec's ``message`` as ``key.path = value, expected ...`` (or "did you mean")."""
    match = _AT.match(message)
    steps = [name or int(index) for name, index in _STEP.findall(match["where"] or "")]
    where = "".join(f"[{s}]" if isinstance(s, int) else f".{s}" for s in steps).lstrip(".")
    what = match["what"]
    unknown = re.match(r"Object contains unknown field `(\w+)`", what)
    if unknown:
        key = unknown[1]
        fields = _table_keys(_type_at(SceneSpec, steps))
        swapped = [f for f in fields if sorted(f) == sorted(key)]  # short keys: "dk" for kd
        close = difflib.get_close_matches(key, fields, n=1) or swapped
        hint = f"did you mean {close[0]!r}?" if close else f"expected one of {', '.join(fields)}"
        return f"{where + '.' if where else ''}{key}: unknown key, {hint}"
    missing = re.match(r"Object missing required field `(\w+)`", what)
    if missing:
        return f"{where + '.' if where else ''}{missing[1]} is missing"
    value = _value_at(data, steps)
    return f"{where} = {value!r}, expected {_describe(_type_at(SceneSpec, steps), what)}"


def _value_at(data, steps: list) -> object:
    for step in steps:
        data = data[step]
    return data


def _type_at(tp, steps: list):
    """The declared type at ``steps`` below ``tp`` (struct fields, list and tuple items)."""
    for step in steps:
        tp = _plain(tp)
        if isinstance(step, str):
            tp = typing.get_type_hints(tp, include_extras=True)[step]
        else:
            args = [a for a in typing.get_args(tp) if a is not type(None)]
            tp = args[step] if typing.get_origin(tp) is tuple else args[0]
    return tp


def _table_keys(tp) -> tuple[str, ...]:
    """The keys of the table declared as ``tp``: a struct, optional or in a union."""
    tp = _plain(tp)
    if isinstance(tp, type) and issubclass(tp, msgspec.Struct):
        return tp.__struct_fields__
    return tuple(key for arg in typing.get_args(tp) for key in _table_keys(arg))


def _plain(tp):
    """``tp`` without Annotated and without None in a union."""
    if typing.get_origin(tp) is Annotated:
        tp = typing.get_args(tp)[0]
    args = [a for a in typing.get_args(tp) if a is not type(None)]
    if type(None) in typing.get_args(tp) and len(args) == 1:
        return _plain(args[0])
    return tp


def _describe(tp, fallback: str) -> str:
    """What a value of the declared type ``tp`` must be, in words."""
    args = typing.get_args(tp)
    if type(None) in args and len(args) == 2:  # optional: what it is when given
        return _describe(next(a for a in args if a is not type(None)), fallback)
    annotated = typing.get_origin(tp) is Annotated
    meta = [m for m in args[1:] if isinstance(m, msgspec.Meta)] if annotated else []
    if meta and meta[0].description:
        return meta[0].description
    base = _plain(tp)
    if typing.get_origin(base) is Literal:
        return "one of " + ", ".join(map(str, typing.get_args(base)))
    if typing.get_origin(base) is list and not (meta and meta[0].min_length == 3):
        return "a list, each " + _describe(typing.get_args(base)[0], fallback)
    if typing.get_origin(base) in (tuple, list):
        return "[x, y, z] (three numbers" + _bounds(typing.get_args(base)[0]) + ")"
    if base is int and meta and meta[0].le is not None:
        return f"a whole number in {meta[0].ge}..{meta[0].le}"
    if base in (float, int):
        return ("a whole number" if base is int else "a number") + _bounds(tp)
    if base is str:
        return "a string"
    if typing.get_args(base):
        return " or ".join(_describe(a, fallback) for a in typing.get_args(base))
    return fallback.replace("Expected ", "").replace("`", "")


def _bounds(tp) -> str:
    """`` in [a, b]``, `` > 0`` and the like, from an Annotated number's Meta."""
    meta = next((m for m in typing.get_args(tp)[1:] if isinstance(m, msgspec.Meta)), None)
    if meta is None:
        return ""
    low = (meta.ge, "[") if meta.ge is not None else (meta.gt, "(")
    high = (meta.le, "]") if meta.le is not None else (meta.lt, ")")
    if high[0] is not None and abs(high[0]) >= _LIMIT:
        if low[0] is not None and abs(low[0]) >= _LIMIT:
            return ", finite"
        return f" {'>=' if low[1] == '[' else '>'} {low[0]:g}"
    if low[0] is None:
        return f" {'<=' if high[1] == ']' else '<'} {high[0]:g}"
    if high[0] is None:
        return f" {'>=' if low[1] == '[' else '>'} {low[0]:g}"
    return f" in {low[1]}{low[0]:g}, {high[0]:g}{high[1]}"


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
    """Builds nodes from a checked :class:`SceneSpec`, finding files beside the scene."""

    def __init__(self, path: Path):
        self.path = path

    def find(self, name: str) -> Path:
        for base in (self.path.parent, asset_root()):
            candidate = base / name
            if candidate.is_file():
                return candidate
        raise InputFileError(f"{self.path}: referenced file {name!r} not found")

    def node(self, index: int, spec: ObjectSpec) -> Node:
        mesh = self.mesh(spec, f"object[{index}]")
        if spec.fit is not None:
            mesh = mesh.fitted(spec.fit)
        mat = spec.material
        kd = (mat.kd,) * 3 if isinstance(mat.kd, float) else tuple(mat.kd)
        material = Material(
            kd=kd,
            fresnel=self.fresnel(mat.fresnel, f"object[{index}].material.fresnel"),
            phong_exponent=mat.phong_exponent,
            sharpness=mat.sharpness,
            tangent_field=TangentField(mat.tangent_field, mat.tangent_axis),
            model=mat.model,
        )
        transform = Transform(spec.translation, spec.rotation, spec.scale)
        name = spec.name or f"object{index}"
        return Node(name, mesh, material, transform, spec.role, spec.color)

    def fresnel(self, value: float | list[float] | str, where: str) -> tuple[float, float, float]:
        """f_λ as linear RGB: a grey, three numbers or a preset's name (core/presets.py)."""
        if isinstance(value, float):
            return (value,) * 3
        if not isinstance(value, str):
            return tuple(value)
        if value.strip().lower() not in FRESNEL_RGB:
            raise InputFileError(
                f"{self.path}: {where} = {value!r}: expected a number in [0, 1], three of them "
                f"or one of {', '.join(FRESNEL_RGB)}"
            )
        return FRESNEL_RGB[value.strip().lower()]

    def mesh(self, spec: ObjectSpec, where: str) -> MeshData:
        if spec.mesh is not None:
            mesh = load_mesh(self.find(spec.mesh), spec.components)
            return loop_subdivided(mesh, spec.subdivide) if spec.subdivide else mesh
        makers = {
            "sphere": lambda: uv_sphere(spec.size / 2),
            "box": lambda: box(spec.size),
            "room": lambda: box(spec.size, inward=True),
        }
        if spec.primitive not in makers:
            raise InputFileError(
                f'{self.path}: {where} needs mesh = "file" or primitive = sphere|box|room'
            )
        return makers[spec.primitive]()
