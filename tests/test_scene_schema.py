"""Scene files against their schema (issue 38 item 12): every table, and fuzzed documents.

A misspelt key in any table of :class:`~envstudio.io.scene_file.SceneSpec` (optional
tables and unions of them included) is one line with "did you mean"; any document made
of the schema's keys, with values of any type and keys misspelt or left out, loads or
raises the one-line UserError.
"""

from __future__ import annotations

import copy
import json
import math
import typing

import msgspec
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from envstudio.errors import InputFileError, UserError
from envstudio.io.images import write_image
from envstudio.io.scene_file import SceneSpec, load_scene

#: A valid scene with every table of the schema (the environment written beside it).
BASE = {
    "name": "fuzz",
    "environment": {"file": "env.exr"},
    "camera": {"azimuth": 10.0},
    "proxy": {"shape": "sphere", "centre": [0.0, 0.0, 0.0], "radius": 3.0},
    "object": [{"primitive": "sphere", "material": {"kd": 0.1}}],
}


def _structs(tp) -> list[type]:
    """The msgspec structs a declared type names: itself, optional, in a union or a list."""
    if isinstance(tp, type) and issubclass(tp, msgspec.Struct):
        return [tp]
    return [s for arg in typing.get_args(tp) for s in _structs(arg)]


def _tables(struct: type = SceneSpec, path: tuple = ()) -> list[tuple[tuple, type]]:
    """(path, struct) of every table below ``struct``; a list of tables is its item 0."""
    found = [(path, struct)]
    for name, hint in typing.get_type_hints(struct, include_extras=True).items():
        listed = "list" in str(hint)
        for inner in _structs(hint):
            found += _tables(inner, path + ((name, 0) if listed else (name,)))
    return found


TABLES = _tables()


def _at(document: dict, path: tuple) -> dict:
    for step in path:
        document = document[step]
    return document


def _toml(value) -> str:
    """``value`` as a TOML value (tables inline)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, (int, float, str)):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return "{" + ", ".join(f"{json.dumps(k)} = {_toml(v)}" for k, v in value.items()) + "}"


def _document(data: dict) -> str:
    return "".join(f"{json.dumps(key)} = {_toml(value)}\n" for key, value in data.items())


def _misspelt(key: str) -> str:
    """``key`` with its last two letters swapped (or doubled where they are the same)."""
    swapped = key[:-2] + key[-1] + key[-2]
    return swapped if swapped != key else key + key[-1]


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A folder with the scenes' tiny environment."""
    path = tmp_path_factory.mktemp("scenes")
    write_image(path / "env.exr", np.full((8, 16, 3), 0.5, np.float32))
    return path


def test_the_base_scene_loads_and_every_table_is_reached(folder):
    (folder / "base.toml").write_text(_document(BASE))
    assert load_scene(folder / "base.toml").name == "fuzz"
    names = {struct.__name__ for _, struct in TABLES}
    assert names == {"SceneSpec", "EnvironmentSpec", "CameraSpec", "ProxySpec", "ObjectSpec",
                     "MaterialSpec"}  # fmt: skip


@pytest.mark.parametrize(
    ("path", "struct"), TABLES, ids=[".".join(map(str, p)) or "top" for p, _ in TABLES]
)
def test_a_misspelt_key_in_every_table_is_did_you_mean(folder, path, struct):
    for key in struct.__struct_fields__:
        data = copy.deepcopy(BASE)
        _at(data, path)[_misspelt(key)] = 1.0
        scene = folder / "misspelt.toml"
        scene.write_text(_document(data))
        with pytest.raises(InputFileError) as error:
            load_scene(scene)
        message = str(error.value)
        assert "\n" not in message and f"did you mean {key!r}" in message, message


SCALARS = st.one_of(
    st.booleans(),
    st.integers(-(2**63), 2**63 - 1),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=6),
    st.sampled_from(["sphere", "box", "room", "gold", "axis", "y", "banks", "env.exr"]),
)
VALUES = st.recursive(
    SCALARS,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=4), inner, max_size=3)
    ),
    max_leaves=6,
)


@st.composite
def documents(draw) -> dict:
    """The base scene with a few of its tables' keys set to any value, misspelt or removed."""
    data = copy.deepcopy(BASE)
    for _ in range(draw(st.integers(1, 4))):
        path, struct = draw(st.sampled_from(TABLES))
        table = _at(data, path) if _reachable(data, path) else None
        if not isinstance(table, dict):
            continue
        key = draw(st.sampled_from(struct.__struct_fields__))
        action = draw(st.sampled_from(["set", "misspell", "remove"]))
        if action == "remove":
            table.pop(key, None)
        else:
            table[key if action == "set" else _misspelt(key)] = draw(VALUES)
    return data


def _reachable(data, path: tuple) -> bool:
    try:
        _at(data, path)
    except (KeyError, IndexError, TypeError):
        return False
    return True


@settings(max_examples=1500, deadline=None, derandomize=True)
@given(documents())
def test_any_scene_document_loads_or_is_one_line(folder, data):
    scene = folder / "fuzz.toml"
    scene.write_text(_document(data))
    try:
        load_scene(scene)
    except UserError as exc:
        message = str(exc)
        assert message and "\n" not in message, message
