"""es.error_curve (issue 40 items 5, 6): each method's approximation error against the exact
reference across Phong exponents, the numbers compare reports at each N."""

from __future__ import annotations

import math

import pytest

import envstudio as es
from envstudio import api
from envstudio.measure.error_curve import NO_EXPONENT
from test_reference_cache import _gradient
from test_render_gl import sphere_scene

SIZE, SSAA = (32, 32), 2
EXPONENTS = (20.0, 200.0, 2000.0)


@pytest.fixture(scope="module")
def sphere():
    return sphere_scene(_gradient(), rings=16)


@pytest.fixture(scope="module")
def curve(sphere):
    methods = ["mirror", "hwconv", "kautz", "banks"]
    return api.error_curve(sphere, methods, exponents=EXPONENTS, size=SIZE, ssaa=SSAA)


def test_each_point_is_compares_row_at_that_exponent(sphere, curve):
    assert curve["exponents"] == list(EXPONENTS)
    assert sorted(curve["methods"]) == ["hwconv", "kautz", "mirror"]
    assert curve["notes"] == [f"banks: reflectance model banks {NO_EXPONENT}"]
    report = es.compare(
        sphere,
        ["mirror", "hwconv", "kautz"],
        size=SIZE,
        ssaa=SSAA,
        frames=1,
        reference="exact",
        trace=False,
        phong_exponent=EXPONENTS[1],
    )
    for name, row in report.json["methods"].items():
        measured = curve["methods"][name]
        assert measured["median_relative_error"][1] == row["median_relative_error"]
        assert measured["psnr_db"][1] == row["psnr_db"]


def test_hwconvs_error_is_small_and_below_the_unblurred_methods_on_a_broad_lobe(curve):
    """hwconv convolves with the Phong lobe itself: its error stays within the map's
    resolution (about 1 % at N = 2000 on this 32 x 16 map, as the mirror's) at every N, and
    on the broadest lobe it is well below the mirror's (no blur) and kautz's (a mip level)."""
    errors = {name: m["median_relative_error"] for name, m in curve["methods"].items()}
    assert all(0.0 < e < 0.02 for e in errors["hwconv"])
    assert errors["hwconv"][0] < errors["mirror"][0] / 3
    assert errors["hwconv"][0] < errors["kautz"][0] / 2
    psnr = curve["methods"]["hwconv"]["psnr_db"]
    assert all(p > 40.0 for p in psnr)


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"exponents": []}, "exponents []: expected a list of Phong exponents"),
        ({"exponents": "100"}, "expected a list of Phong exponents"),
        ({"exponents": [100, math.inf]}, "expected a list of Phong exponents"),
        ({"exponents": [0.5]}, "0.5 is outside hwconv's phong_exponent range 1..10000"),
        ({"methods": ["banks"]}, "none has an exact reference"),
        ({"methods": ["phong"]}, "unknown method 'phong'"),
        ({"size": (4, 4)}, "size (4, 4)"),
        ({"ssaa": 0}, "ssaa 0"),
        ({"camera": (0, 0)}, "camera (0, 0)"),
        ({"phong_exponent": 50}, "phong_exponent: error_curve sets it"),
        ({"border": "wide"}, "border"),
        ({"lod_bias": 2.0, "methods": ["mirror"]}, "lod_bias"),
    ],
)
def test_bad_arguments_are_one_line_user_errors(sphere, arguments, message):
    arguments = {"methods": ["hwconv"], **arguments}
    with pytest.raises(es.UserError, match=None) as raised:
        api.error_curve(sphere, **arguments)
    assert message in str(raised.value)
    assert "\n" not in str(raised.value)


def test_a_method_that_refuses_an_exponent_is_nan_there_with_a_note(sphere):
    """hwconv's default border is too narrow for N = 5's kernel: NaN and a note at that N;
    the mirror, measured alone then, keeps its numbers."""
    curve = api.error_curve(sphere, "hwconv,mirror", exponents=[5], size=SIZE, ssaa=1)
    assert math.isnan(curve["methods"]["hwconv"]["median_relative_error"][0])
    assert math.isfinite(curve["methods"]["mirror"]["psnr_db"][0])
    assert curve["notes"][0].startswith("hwconv at N = 5: border=36: expected an integer >= ")
