"""Saved exact frames (measure/exact_cache.py): keyed by what the model reads, read back whole."""

from __future__ import annotations

import json

import numpy as np

from envstudio.measure.exact_cache import exact_path, load_frame, save_frame
from envstudio.measure.exact_reference import CheckedError, ExactFrame
from test_compare import compare, small_scene  # noqa: F401 (a fixture)

BANKS = {"model": "banks", "fresnel": [0.9] * 3, "kd": [0.0] * 3, "phong_exponent": 10.0}
BANKS |= {"sharpness": 0.9, "normalize": True, "self_shadowing": False}
BANKS |= {"tangent_field": "axis", "tangent_axis": "y"}


def _inputs(seed: int = 0):
    rng = np.random.default_rng(seed)
    radiance = rng.random((8, 16, 3), dtype=np.float32)
    normals, views, tangents = (rng.random((12, 12, 3), dtype=np.float32) for _ in range(3))
    return radiance, normals, views, tangents


def test_the_key_follows_the_values_the_model_reads_and_every_input_array():
    """Banks' lobe reads no N: its frames at N = 10 and 1000 are one; GGX's α is N's, so its
    are two; a changed texel, sample, Banks value or ssaa is another frame."""
    radiance, n, v, t = _inputs()
    banks = exact_path(radiance, n, v, t, BANKS, 4)
    assert exact_path(radiance, n, v, t, BANKS | {"phong_exponent": 1000.0}, 4) == banks
    microfacet = BANKS | {"model": "microfacet"}
    assert exact_path(radiance, n, v, None, microfacet, 4) != exact_path(
        radiance, n, v, None, microfacet | {"phong_exponent": 1000.0}, 4
    )
    changed = radiance.copy()
    changed[3, 5, 1] += 1e-3
    others = {
        exact_path(changed, n, v, t, BANKS, 4),
        exact_path(radiance, n, v[::-1].copy(), t, BANKS, 4),
        exact_path(radiance, n, v, t, BANKS | {"sharpness": 0.8}, 4),
        exact_path(radiance, n, v, t, BANKS | {"kd": [0.1] * 3}, 4),
        exact_path(radiance, n, v, t, BANKS, 2),
        exact_path(radiance, n, v, None, BANKS | {"model": "phong"}, 4),
    }
    assert banks not in others and len(others) == 6


def test_a_saved_frame_reads_back_equal(tmp_path):
    rng = np.random.default_rng(1)
    hdr = rng.random((6, 6, 3), dtype=np.float32)
    frame = ExactFrame(hdr, hdr[..., 0] > 0.5, CheckedError(1e-4, 3e-3, 12, 0.087), 12.5)
    path = tmp_path / "exact" / "frame.npz"
    assert load_frame(path) is None
    save_frame(path, frame)
    back = load_frame(path)
    np.testing.assert_array_equal(back.hdr, frame.hdr)
    np.testing.assert_array_equal(back.mask, frame.mask)
    assert (back.error, back.seconds) == (frame.error, frame.seconds)


def test_a_second_compare_reads_the_exact_reference_back(small_scene, tmp_path, capsys):  # noqa: F811
    """compare keeps its exact frames (its cache on): the same view again reads them back and
    reports the same numbers; with --no-cache it evaluates them again."""
    args = ["--methods", "mirror", "--reference", "exact", "--ssaa", "2"]
    assert compare(small_scene, tmp_path / "one", *args) == 0
    first = capsys.readouterr().err
    assert "reference: exact in" in first and "read back" not in first
    assert compare(small_scene, tmp_path / "two", *args) == 0
    second = capsys.readouterr().err
    assert "reference: exact read back (evaluated in" in second
    one, two = (json.loads((tmp_path / d / "compare.json").read_text()) for d in ("one", "two"))
    for number in ("psnr_db", "flip", "median_relative_error"):
        assert one["methods"]["mirror"][number] == two["methods"]["mirror"][number]
    assert compare(small_scene, tmp_path / "three", *args, "--no-cache") == 0
    assert "read back" not in capsys.readouterr().err
