"""Glossiness matching (seed 000 §4.2, §6, Figure 5) and the NumPy box mip chain (no GL)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from envstudio.core import cubemap
from envstudio.core.env_sampling import luminance
from envstudio.core.resample import latlong_to_cube, sample_cube
from envstudio.io.images import read_environment
from envstudio.io.scene_file import shipped_environments
from envstudio.prefilter import glossiness
from envstudio.prefilter.mip_chain import (
    box_mip_chain,
    level_samples,
    sample_mip_chain,
    trilinear,
)

SIZES = np.array([16, 64, 128, 256, 512, 2048])
HELD_OUT = ("interior", "studio", "sunrise")


def random_faces(n: int, seed: int = 3) -> np.ndarray:
    return np.random.default_rng(seed).uniform(0.0, 4.0, size=(6, n, n, 3))


def random_directions(count: int, seed: int = 5) -> np.ndarray:
    d = np.random.default_rng(seed).normal(size=(count, 3))
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


# --- the mip chain --------------------------------------------------------------------------


def test_level_k_is_the_box_mean_of_level_0():
    faces = random_faces(16)
    chain = box_mip_chain(faces)
    assert [level.shape[1] for level in chain] == [16, 8, 4, 2, 1]
    for k, level in enumerate(chain):
        m = 16 >> k
        box = faces.reshape(6, m, 1 << k, m, 1 << k, 3).mean(axis=(2, 4))
        np.testing.assert_allclose(level, box, rtol=1e-12)
    np.testing.assert_allclose(chain[-1][:, 0, 0], faces.mean(axis=(1, 2)), rtol=1e-12)


def test_mip_chain_needs_a_power_of_two():
    with pytest.raises(ValueError, match="power of two"):
        box_mip_chain(random_faces(12))


def test_top_level_at_a_face_centre_is_the_face_mean():
    faces = random_faces(8)
    axes = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    top = sample_mip_chain(box_mip_chain(faces), axes, 3.0)
    np.testing.assert_allclose(top, faces.mean(axis=(1, 2)), rtol=1e-6)


def test_integer_level_lookup_is_that_levels_bilinear_sample():
    chain = box_mip_chain(random_faces(16))
    dirs = random_directions(200)
    for k, level in enumerate(chain):
        np.testing.assert_allclose(
            sample_mip_chain(chain, dirs, float(k)), sample_cube(level, dirs), rtol=1e-6
        )


def test_fractional_level_mixes_neighbours_and_level_is_clamped():
    chain = box_mip_chain(random_faces(16))
    dirs = random_directions(50)
    s1, s2 = sample_cube(chain[1], dirs), sample_cube(chain[2], dirs)
    np.testing.assert_allclose(sample_mip_chain(chain, dirs, 1.25), 0.75 * s1 + 0.25 * s2, 1e-6)
    samples = level_samples(chain, dirs)
    np.testing.assert_allclose(trilinear(samples, -2.0), samples[0])
    np.testing.assert_allclose(trilinear(samples, 9.0), samples[-1])
    per_direction = np.linspace(0.0, 4.0, len(dirs))
    expected = [trilinear(samples[:, i], level) for i, level in enumerate(per_direction)]
    np.testing.assert_allclose(trilinear(samples, per_direction), expected)


# --- the mapping ----------------------------------------------------------------------------


def test_bias_and_exponent_are_inverses():
    N = np.geomspace(0.1, 1e5, 301)[:, None]
    b = glossiness.lod_bias_for_exponent(N, SIZES)
    assert b.shape == (301, len(SIZES))
    N_back = glossiness.exponent_for_lod_bias(b, SIZES)
    np.testing.assert_allclose(N_back, np.broadcast_to(N, b.shape), rtol=1e-6)
    biases = np.concatenate([np.linspace(-3.0, 12.0, 451), np.arange(-3.0, 13.0)])[:, None]
    b_back = glossiness.lod_bias_for_exponent(
        glossiness.exponent_for_lod_bias(biases, SIZES), SIZES
    )
    np.testing.assert_allclose(b_back, np.broadcast_to(biases, b_back.shape), atol=1e-6)


def test_bias_grows_as_the_exponent_falls_and_with_the_cube():
    N = np.geomspace(0.5, 1e4, 500)
    b = glossiness.lod_bias_for_exponent(N[:, None], SIZES)
    assert np.all(np.diff(b, axis=0) < 0.0)
    assert np.all(np.diff(b, axis=1) > 0.0)


def test_trilinear_level_is_continuous_and_fixes_integers():
    k = np.arange(-2.0, 10.0)
    np.testing.assert_allclose(glossiness.trilinear_level(k), k)
    np.testing.assert_allclose(glossiness.trilinear_level(k - 1e-9), k, atol=1e-8)


def test_bad_exponent_or_size_is_refused():
    with pytest.raises(ValueError, match="Phong exponent"):
        glossiness.lod_bias_for_exponent(0.0, 256)
    with pytest.raises(ValueError, match="cube size"):
        glossiness.exponent_for_lod_bias(2.0, -1)


def test_best_level_recovers_a_planted_level():
    chain = box_mip_chain(random_faces(32))
    samples = luminance(level_samples(chain, random_directions(300)))
    reference = trilinear(samples[..., None], 2.3)[..., 0]
    assert glossiness.best_level(samples, reference) == pytest.approx(2.3, abs=1e-3)


def test_stored_fit_is_package_data_and_holds_out_the_test_maps():
    fit = json.loads(glossiness.DATA_FILE.read_text(encoding="utf-8"))
    assert glossiness.DATA_FILE.parent.parent.name == "envstudio"
    assert not set(HELD_OUT) & set(fit["settings"]["environments"])
    assert fit["model"]["residual_rms"] < 0.25
    assert fit["model"]["coefficients"]["c"] == pytest.approx(1.0, abs=0.02)


@pytest.mark.parametrize("name", HELD_OUT)
def test_fitted_bias_beats_half_a_level_either_way_on_a_held_out_map(name):
    """At Figure 5's N = 225 the fitted b reproduces the brute-force Phong prefilter
    (prefilter.brute_force) better than b ± ½ on an environment the fit never saw."""
    image = read_environment(shipped_environments()[name])
    dirs = glossiness.fibonacci_directions(512)
    size, exponent = 64, 225.0
    samples = luminance(level_samples(box_mip_chain(latlong_to_cube(image, size)), dirs))
    reference = glossiness.phong_reference(image, dirs, exponent)
    b = float(glossiness.lod_bias_for_exponent(exponent, size))
    below, fitted, above = glossiness.level_error(samples, reference, [b - 0.5, b, b + 0.5])
    assert fitted < 0.8 * min(below, above)


def test_cube_directions_match_the_chain_layout():
    """The lookup indexes faces like core.cubemap: texel centres read back their own value."""
    faces = random_faces(4)
    chain = box_mip_chain(faces)
    centres = cubemap.texel_directions(4)
    np.testing.assert_allclose(sample_mip_chain(chain, centres, 0.0), faces, rtol=1e-6)
