"""The Python API's arguments, checked at its boundary with the command line's declarations.

Private to :mod:`envstudio.api`: each function takes a value as a caller passed it and returns
it as the API uses it, or raises a :class:`~envstudio.errors.ParameterError` whose one line
names the argument and what was expected. The checks are the CLI's own (``--size``,
``--camera``, ``--time-limit``, ``--ssaa``, ``--param``'s declared parameters, the display's
settings); what the command line's text cannot get wrong (a type) is checked here first.
"""

from __future__ import annotations

import numbers
import os
from collections.abc import Mapping, Sequence

import numpy as np
import numpy.typing as npt

from envstudio.core.parameters import parse_assignments
from envstudio.engine.display import DISPLAY_PARAMETERS
from envstudio.engine.method import Method
from envstudio.engine.registry import method_class
from envstudio.errors import ParameterError
from envstudio.io.images import MAX_RADIANCE
from envstudio.io.scene_setup import check_camera, check_size
from envstudio.scene.graph import Scene

_DISPLAY = {p.name: p for p in DISPLAY_PARAMETERS}


def _shown(value: object) -> str:
    """``value`` in a message: an array by its shape and type, anything else by its repr."""
    if isinstance(value, np.ndarray):
        return f"of shape {value.shape} {value.dtype}"
    return f"{value!r}"[:80]


def _integer(value: object) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_))


def _real(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def scene(value: object) -> Scene:
    """A scene from :func:`envstudio.load_scene`."""
    if not isinstance(value, Scene):
        raise ParameterError(f"scene {_shown(value)}: expected a Scene from es.load_scene()")
    return value


def path(value: object, name: str, expected: str) -> str | os.PathLike | None:
    """A file or scene name (str or path-like), or None."""
    if value is not None and not isinstance(value, (str, os.PathLike)):
        raise ParameterError(f"{name} {_shown(value)}: expected {expected}")
    return value


def integer(value: object, name: str, minimum: int | None = None) -> int:
    """An integer (of at least ``minimum``, when given)."""
    if not _integer(value) or (minimum is not None and value < minimum):
        at_least = "" if minimum is None else f" >= {minimum}"
        raise ParameterError(f"{name} {_shown(value)}: expected an integer{at_least}")
    return int(value)


def flag(value: object, name: str) -> bool:
    """True or False."""
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name} {_shown(value)}: expected True or False")
    return bool(value)


def method(value: object) -> type[Method]:
    """The registered method class called ``value``."""
    if not isinstance(value, str):
        raise ParameterError(f"method {_shown(value)}: expected a method name (envstudio methods)")
    return method_class(value)


def methods(value: object) -> list[str]:
    """Method names: a sequence of them, or one string of comma-separated names as
    ``--methods`` takes them; each registered."""
    names = value.split(",") if isinstance(value, str) else value
    if not isinstance(names, Sequence) or not all(isinstance(n, str) for n in names):
        names = []
    names = [n.strip() for n in names if n.strip()]
    if not names:
        raise ParameterError(f"methods {_shown(value)}: expected a list of method names")
    for name in names:
        method_class(name)
    return names


def size(value: object) -> tuple[int, int]:
    """(width, height) in pixels, as ``--size`` allows."""
    edges = tuple(value) if isinstance(value, (tuple, list, np.ndarray)) else ()
    if len(edges) != 2 or not all(_integer(e) for e in edges):
        edges = (0, 0)
    width, height = check_size(edges, f"size {_shown(value)}", "(width, height) integers")
    return int(width), int(height)


def camera(value: object) -> tuple[float, float, float] | None:
    """(azimuth, elevation, distance) as ``--camera`` allows, or None (the scene's own)."""
    if value is None:
        return None
    parts = tuple(value) if isinstance(value, (tuple, list, np.ndarray)) else ()
    if len(parts) != 3 or not all(_real(p) for p in parts):
        raise ParameterError(
            f"camera {_shown(value)}: expected (azimuth, elevation, distance) numbers"
        )
    try:
        placed = tuple(float(p) for p in parts)
    except OverflowError:
        placed = (0.0, 0.0, 0.0)
    return check_camera(placed, f"camera {_shown(value)}")


def _text(name: str, value: object) -> str:
    """A parameter value as ``--param name=...`` writes it (a colour as r,g,b)."""
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value)).lower()
    if isinstance(value, (str, os.PathLike)) or _real(value):
        return os.fspath(value) if isinstance(value, os.PathLike) else str(value)
    if isinstance(value, (tuple, list, np.ndarray)) and all(
        isinstance(v, str) or _real(v) for v in value
    ):
        return ",".join(str(v) for v in value)
    raise ParameterError(
        f"{name}={_shown(value)}: expected a number, a string, True/False or (r, g, b)"
    )


def assignments(parameters: Mapping[str, object]) -> list[str]:
    """``parameters`` as ``--param name=value`` strings (whose values the declarations check).

    Raises
    ------
    ParameterError
        A name that is no identifier, or a value of no type ``--param`` can write.
    """
    texts = []
    for name, value in parameters.items():
        if not name.isidentifier():
            raise ParameterError(f"parameter {name!r}: expected a parameter name")
        texts.append(f"{name}={_text(name, value)}")
    return texts


def method_assignments(cls: type[Method], parameters: Mapping[str, object]) -> list[str]:
    """``parameters`` as ``--param`` strings, each checked against the parameter of that name
    that method ``cls`` or the display declares (the method's first).

    Raises
    ------
    ParameterError
        A name neither declares, or a value its declaration refuses.
    """
    declared = _DISPLAY | {p.name: p for p in cls.parameters}
    texts = assignments(parameters)
    for name, value in parse_assignments(texts).items():
        if name not in declared:
            own = ", ".join(p.name for p in cls.parameters) or "none"
            raise ParameterError(
                f"unknown parameter {name!r} for method {cls.name} "
                f"(method: {own}; display: {', '.join(_DISPLAY)})"
            )
        declared[name].validate(value)
    return texts


def display_setting(name: str, value: object) -> object:
    """``exposure`` or ``tonemap`` as the display's declaration allows."""
    return _DISPLAY[name].validate(value)


def linear_image(value: object) -> npt.NDArray[np.floating]:
    """(h, w, 3) linear radiance, h and w at least 1, each value finite and within
    :data:`~envstudio.io.images.MAX_RADIANCE`."""
    try:
        image = np.asarray(value)
    except (TypeError, ValueError):  # ragged nested lists
        image = np.zeros(0)
    numeric = image.dtype.kind in "fiu"
    if not (numeric and image.ndim == 3 and image.shape[2] == 3 and image.size):
        raise ParameterError(
            f"image {_shown(value)}: expected an (h, w, 3) array of linear radiance"
        )
    if not (np.abs(image) <= MAX_RADIANCE).all():  # NaN too
        raise ParameterError(
            f"image {_shown(value)}: expected finite radiance, each value within "
            f"+-{MAX_RADIANCE:g} (as an environment's)"
        )
    return image


def srgb_image(value: object) -> npt.NDArray[np.uint8] | None:
    """``value`` when it is (h, w, 3) or (h, w, 4) uint8 sRGB; None when it is not uint8."""
    image = value if isinstance(value, np.ndarray) else None
    if image is None or image.dtype != np.uint8:
        return None
    if not (image.ndim == 3 and image.shape[2] in (3, 4) and image.size):
        raise ParameterError(
            f"image {_shown(value)}: expected (h, w, 3) or (h, w, 4) uint8 sRGB, "
            "or (h, w, 3) linear radiance"
        )
    return image
