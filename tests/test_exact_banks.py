"""Issue 40: the exact reference of the untraced Banks model (seed 004 §5.3), and the
refusal of a map too large for the exact tables.

The GPU descent (measure/exact_lobes.py) against a NumPy sum written here from the formula
(every sample), a constant environment (the constant times the albedo (1 − F) k_d + F with
the lobe normalised), and the one-line refusal naming the ``--max-env-width`` that fits.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from envstudio.core.latlong import texel_directions, texel_solid_angles
from envstudio.errors import ParameterError
from envstudio.measure import exact_lobes
from envstudio.measure.exact_lobes import LobeEvaluator
from envstudio.measure.exact_reference import exact_radiance
from test_exact_reference import FRESNEL, KD, random_frames, spot_map

SHARPNESS = (0.5, 0.9, 0.99)


def random_tangents(normals: np.ndarray, seed: int) -> np.ndarray:
    """(s, 3) unit tangents orthogonal to the normals."""
    t = np.cross(normals, np.random.default_rng(seed).normal(size=normals.shape))
    return t / np.linalg.norm(t, axis=1, keepdims=True)


def numpy_banks(radiance, normals, views, tangents, sharpness, shadowing, split=12):
    """F(n·v) ∫ L f_banks [max(n·l, 0)] dl / ∫ f_banks dl + (1 − F) k_d E(n)/π, the map constant
    over each texel: a plain sum over every texel cut into ``split``² parts; the lobe's
    integral by a 1D sum over the angle to t."""
    fine = np.repeat(np.repeat(radiance, split, axis=0), split, axis=1)
    h, w = fine.shape[:2]
    directions = texel_directions(h, w).reshape(-1, 3)
    weighted = fine.reshape(-1, 3).astype(np.float64) * texel_solid_angles(h, w).reshape(-1, 1)
    lt, vt = tangents @ directions.T, np.einsum("sk,sk->s", views, tangents)[:, None]
    lobe = np.maximum(np.sqrt(1 - lt**2) * np.sqrt(1 - vt**2) - lt * vt - sharpness, 0.0)
    if shadowing:
        lobe *= np.maximum(normals @ directions.T, 0.0)
    theta = (np.arange(20000) + 0.5) * np.pi / 20000
    whole = np.maximum(np.sin(theta) * np.sqrt(1 - vt**2) - np.cos(theta) * vt - sharpness, 0.0) @ (
        2 * np.pi * np.sin(theta) * np.pi / 20000
    )
    cos_nv = np.einsum("sk,sk->s", normals, views)
    f = FRESNEL + (1.0 - FRESNEL) * ((1.0 - np.clip(cos_nv, 0, 1)) ** 5)[:, None]
    diffuse = np.maximum(normals @ directions.T, 0.0) / np.pi @ weighted
    out = (1.0 - f) * KD * diffuse + f * (lobe @ weighted) / whole[:, None]
    return np.where((cos_nv > 0)[:, None], out, 0.0)


def banks_values(sharpness: float, shadowing: bool) -> dict[str, object]:
    return {
        "model": "banks",
        "fresnel": FRESNEL,
        "kd": KD,
        "sharpness": sharpness,
        "normalize": True,
        "self_shadowing": shadowing,
    }


@pytest.mark.parametrize("shadowing", [False, True])
@pytest.mark.parametrize("sharpness", SHARPNESS)
def test_every_sample_matches_an_independent_numpy_sum(gl_ctx, programs, sharpness, shadowing):
    radiance = spot_map(16)
    normals, views = random_frames(60, seed=3)
    tangents = random_tangents(normals, seed=4)
    lobes = LobeEvaluator(gl_ctx, programs)
    values = banks_values(sharpness, shadowing)
    exact = exact_radiance(radiance, normals, views, values, lobes, tangents)
    lobes.release()
    expected = numpy_banks(radiance, normals, views, tangents, sharpness, shadowing)
    relative = np.abs(exact - expected).max(axis=1) / expected.max(axis=1)
    assert np.median(relative) < 2e-3 and relative.max() < 1e-2
    assert abs(exact.sum() / expected.sum() - 1.0) < 1e-3


@pytest.mark.parametrize("sharpness", SHARPNESS)
def test_a_constant_environment_gives_the_constant_times_the_albedo(gl_ctx, programs, sharpness):
    radiance = np.full((16, 32, 3), 2.5, np.float32)
    normals, views = random_frames(40, seed=5)
    tangents = random_tangents(normals, seed=6)
    lobes = LobeEvaluator(gl_ctx, programs)
    exact = exact_radiance(
        radiance, normals, views, banks_values(sharpness, False), lobes, tangents
    )
    lobes.release()
    cos_nv = np.einsum("sk,sk->s", normals, views)
    f = FRESNEL + (1.0 - FRESNEL) * ((1.0 - cos_nv) ** 5)[:, None]
    np.testing.assert_allclose(exact, 2.5 * ((1.0 - f) * KD + f), rtol=2e-3)


def test_a_map_too_large_for_the_tables_names_the_width_that_fits(monkeypatch):
    with pytest.raises(ParameterError) as refused:
        exact_lobes.check_size(4096, 8192)
    message = str(refused.value)
    assert "\n" not in message and "--max-env-width 2048" in message
    exact_lobes.check_size(1024, 2048)  # the shipped maps' size and twice it pass
    monkeypatch.setattr(exact_lobes, "MAX_TEXELS", 16 * 32)
    normals, views = random_frames(4, seed=1)
    values = {"model": "phong", "fresnel": FRESNEL, "kd": KD, "phong_exponent": 10.0}
    with pytest.raises(ParameterError, match=r"environment 64x32: .* --max-env-width 32 "):
        exact_radiance(spot_map(32), normals, views, values)
    assert math.isfinite(float(exact_radiance(spot_map(16), normals, views, values).sum()))
