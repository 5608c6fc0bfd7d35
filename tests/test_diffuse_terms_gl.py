"""Each method's own diffuse term (issue 27 part 1) against NumPy brute-force irradiance.

A sphere under a sky with a 5° sun of 200 times its radiance, rendered with
k_d = 1 and 0 (measure.diffuse_check): the difference is (1 − F) E(n)/π by the
method's own means, held over every pixel with n·v > 0.3 against the
brute-force sum over the environment's texels.
"""

import numpy as np
import pytest

from envstudio.measure.diffuse_check import diffuse_errors
from envstudio.scene.environment import Environment
from test_kautz_gl import sun_and_sky


@pytest.mark.parametrize(
    ("method", "settings", "mean", "bias"),
    [
        ("mirror", [], 0.003, 0.002),  # SH 49 + 32 lights by default
        ("hwconv", [], 0.003, 0.002),  # Miller's map from the hierarchical prefilter
        ("banks", [], 0.003, 0.002),
        ("rsibr", [], 0.005, 0.003),  # Lambertian maps of Miller's E/pi, normal warp
        ("rsibr", ["diffuse_maps=baked"], 0.012, 0.01),  # importance-sampled, 1024 samples
        ("kautz", ["sh_coefficients=49", "lights=32", "per_pixel=true"], 0.003, 0.002),
    ],
)
def test_diffuse_part_matches_brute_force_irradiance_under_a_sun(
    gl_ctx, method, settings, mean, bias
):
    (error,) = diffuse_errors(sun_and_sky(64), [(method, settings)], (48, 48), 64, gl_ctx)
    assert error.pixels > 900
    assert error.mean < mean and abs(error.bias) < bias, error


def test_paper_settings_are_measurably_worse_under_the_sun(gl_ctx):
    """The 9-coefficient SH of seed 000 and 256-sample Lambertian maps miss the sun."""
    errors = diffuse_errors(
        sun_and_sky(64),
        [
            ("mirror", ["sh_coefficients=9", "lights=0"]),
            ("rsibr", ["diffuse_maps=baked", "diffuse_samples=256"]),
        ],
        (48, 48),
        64,
        gl_ctx,
    )
    assert all(e.mean > 0.02 for e in errors), errors


def test_constant_environment_gives_the_constant_in_every_method(gl_ctx):
    env = Environment.constant((0.2, 0.4, 0.8), height=64)
    runs = [(m, []) for m in ("mirror", "hwconv", "banks", "rsibr")]
    errors = diffuse_errors(env, runs, (32, 32), 64, gl_ctx)
    assert max(e.maximum for e in errors) < 2e-3, errors
    assert np.isfinite([e.bias for e in errors]).all()
