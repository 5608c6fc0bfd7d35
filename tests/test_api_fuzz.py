"""Issue 38 item 6, fuzzed: random values of every argument's type and of wrong types.

The property of every public function and of the ``--param`` parser: it returns a valid
result or raises a one-line :class:`UserError`, and the next good call still works (a render
equal to a fresh one). Bounded and derandomized, so that CI sees the same examples.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import envstudio as es
from envstudio.core.parameters import parse_assignments
from envstudio.engine.display import DISPLAY_PARAMETERS
from envstudio.engine.registry import available_methods

SIZE = (8, 8)
FUZZ = settings(
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],  # the autouse ones
)

JUNK = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**20), 10**20),
    st.floats(),
    st.text(max_size=8),
    st.tuples(st.floats(), st.integers(-3, 3)),
    st.lists(st.one_of(st.floats(-2, 2), st.text(max_size=2)), max_size=4),
    st.dictionaries(st.text(max_size=2), st.integers(), max_size=1),
)


def or_junk(valid: st.SearchStrategy) -> st.SearchStrategy:
    """``valid`` values, and now and then (about one time in five) a value of any type."""
    return st.integers(0, 4).flatmap(lambda k: JUNK if k == 4 else valid)


NAMES = ["fresnel", "kd", "lights", "light_threshold", "lod_bias", "per_pixel", "bogus"]
NAMES += [p.name for p in DISPLAY_PARAMETERS]
VALUES = or_junk(st.sampled_from(["gold", "aces", "none", "true", "0.5", "2", "1,0,0", 0.5, True]))


@pytest.fixture(scope="module")
def studio():
    return es.load_scene("studio")


@pytest.fixture(scope="module")
def fresh(studio):
    return es.render(studio, "mirror", size=SIZE)


def _refused_in_one_line(error: es.UserError) -> None:
    assert str(error) and "\n" not in str(error)


def _still_renders(studio, fresh) -> None:
    np.testing.assert_array_equal(es.render(studio, "mirror", size=SIZE), fresh)


@settings(FUZZ, max_examples=100)
@given(
    method=or_junk(st.sampled_from(["mirror", "kautz", "phong"])),
    size=or_junk(st.tuples(st.integers(0, 12), st.integers(1, 12))),
    camera=or_junk(st.none() | st.tuples(st.floats(), st.floats(-100, 100), st.floats(-1, 10))),
    parameters=st.dictionaries(st.sampled_from(NAMES), VALUES, max_size=3),
)
def test_render_returns_a_frame_or_refuses(studio, fresh, method, size, camera, parameters):
    try:
        img = es.render(studio, method, size=size, camera=camera, **parameters)
    except es.UserError as error:
        _refused_in_one_line(error)
    else:
        assert img.dtype == np.float32 and img.shape == (size[1], size[0], 3)
        assert np.isfinite(img).all()
    _still_renders(studio, fresh)


@settings(FUZZ, max_examples=150)
@given(
    image=st.one_of(
        hnp.arrays(
            st.sampled_from([np.float32, np.float64, np.uint8, np.int16, np.bool_]),
            hnp.array_shapes(min_dims=0, max_dims=3, min_side=0, max_side=5),
        ),
        JUNK,
    ),
    exposure=or_junk(st.floats(-12, 12)),
    tonemap=or_junk(st.sampled_from(["none", "reinhard", "aces"])),
)
def test_display_and_show_return_srgb_or_refuse(image, exposure, tonemap):
    for show in (False, True):
        try:
            result = (
                es.show(image, exposure, tonemap) if show else es.display(image, exposure, tonemap)
            )
        except es.UserError as error:
            _refused_in_one_line(error)
            continue
        pixels = result.pixels if show else result
        assert pixels.dtype == np.uint8 and pixels.ndim == 3 and pixels.shape[2] in (3, 4)
        assert np.asarray(image).shape[:2] == pixels.shape[:2]
    assert es.display(np.ones((2, 2, 3))).shape == (2, 2, 3)


@settings(FUZZ, max_examples=25)
@given(
    name=or_junk(st.sampled_from(["studio", "room", "nowhere.toml", None])),
    env=or_junk(st.none()),
    mesh=or_junk(st.none()),
    width=or_junk(st.none() | st.integers(0, 64)),
)
def test_load_scene_returns_a_scene_or_refuses(studio, fresh, name, env, mesh, width):
    try:
        scene = es.load_scene(name, env, mesh, width)
    except es.UserError as error:
        _refused_in_one_line(error)
    else:
        assert scene.reflectors()
    _still_renders(studio, fresh)


@settings(FUZZ, max_examples=16)
@given(
    methods=or_junk(st.sampled_from([["mirror"], "mirror", ("mirror",), ["phong"]])),
    size=or_junk(st.tuples(st.integers(12, 20), st.integers(12, 20))),
    ssaa=or_junk(st.integers(1, 8)),
    frames=or_junk(st.integers(1, 2)),
    cache=or_junk(st.booleans()),
)
def test_compare_reports_or_refuses(studio, fresh, methods, size, ssaa, frames, cache):
    try:
        report = es.compare(
            studio, methods, size, ssaa=ssaa, frames=frames, cache=cache, max_samples=16
        )
    except es.UserError as error:
        _refused_in_one_line(error)
    else:
        assert [row["method"] for row in report.table] == ["mirror"]
    _still_renders(studio, fresh)


DECLARED = [p for m in available_methods().values() for p in m.parameters]
DECLARED += list(DISPLAY_PARAMETERS)


@settings(FUZZ, max_examples=300)
@given(
    declared=st.sampled_from(DECLARED),
    items=st.lists(st.one_of(st.text(max_size=12), JUNK.map(str)), min_size=1, max_size=3),
)
def test_the_param_parser_parses_or_refuses(declared, items):
    """``--param name=value``: the assignment parser and every declared parameter."""
    try:
        values = parse_assignments(items)
    except es.UserError as error:
        _refused_in_one_line(error)
        values = {}
    for value in [*values.values(), *items]:
        try:
            valid = declared.validate(value)
        except es.UserError as error:
            _refused_in_one_line(error)
        else:  # a valid value of its kind, which the declaration takes again as it is
            assert declared.validate(valid) == valid
