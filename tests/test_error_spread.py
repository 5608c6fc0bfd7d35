"""Issue 40 item 2: a control-variate reference judges each method by how far its own noise,
known per pixel, can move the method's median error (stopping.median_error_spread).

Synthetic cases with known answers, the judgement built on them, and compare on a convex
sphere: nothing is left to sample, so the trace stops at its first judgement.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from envstudio.cli import main
from envstudio.core.env_sampling import LUMINANCE
from envstudio.measure.stopping import NOISE_SHARE, Judgement, median_error_spread
from scene_files import ball_scene
from test_exact_reference import spot_map


def frames_with_errors(errors: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A grey reference of 1 and a method frame whose relative error is ``errors`` (h, w),
    with a full mask."""
    reference = np.ones((*errors.shape, 3), np.float32)
    method = (1.0 + errors)[..., None] * reference / float(np.sum(LUMINANCE))
    return (
        method.astype(np.float32),
        reference / float(np.sum(LUMINANCE)),
        np.ones(errors.shape, bool),
    )


@pytest.fixture
def errors() -> np.ndarray:
    """(64, 64) relative errors spread evenly over [0, 0.2], in random places."""
    rng = np.random.default_rng(5)
    return rng.permutation(np.linspace(0.0, 0.2, 64 * 64)).reshape(64, 64)


def test_an_exact_reference_moves_no_median(errors):
    method, reference, mask = frames_with_errors(errors)
    assert median_error_spread(method, reference, np.zeros(errors.shape), mask) == 0.0


def test_noise_at_every_pixel_moves_the_median_by_that_noise(errors):
    """σ everywhere: the median error moves by σ (1 + e) at the median, the plain rule's
    measure of a reference noisy everywhere."""
    method, reference, mask = frames_with_errors(errors)
    sigma = 0.004
    spread = median_error_spread(method, reference, np.full(errors.shape, sigma), mask)
    assert spread == pytest.approx(sigma * (1.0 + np.median(errors)), rel=0.02)


def test_a_few_noisy_pixels_move_the_median_by_their_share_of_ranks_however_noisy(errors):
    """A tenth of the pixels unknown (inf noise): the median can only move by a tenth of the
    ranks each way: from the 4/9 to the 5/9 quantile of the others (errors even over
    [0, 0.2]: half of 0.2 / 9)."""
    method, reference, mask = frames_with_errors(errors)
    noise = np.zeros(errors.shape)
    noise.flat[::10] = np.inf
    spread = median_error_spread(method, reference, noise, mask)
    assert spread == pytest.approx(0.5 * 0.2 / 9.0, rel=0.05)


def test_the_judgement_takes_each_method_s_spread_over_the_median_noise():
    """A control variate's median noise where it traces (2 %) would mark both methods; their
    spreads mark only the one whose median it can move by a tenth of its error."""
    judgement = Judgement(
        batches=8,
        samples=64,
        seconds=1.0,
        noise=0.02,
        errors={"good": 0.05, "close": 0.05},
        spreads={"good": 0.001, "close": 0.01},
    )
    assert judgement.reliable("good") and not judgement.reliable("close")
    assert judgement.shortfall == pytest.approx(2.0)
    plain = Judgement(8, 64, 1.0, 0.02, {"good": 0.05})
    assert not plain.reliable("good") and plain.shortfall == pytest.approx(4.0)


def test_compare_of_a_traced_sphere_stops_though_its_rim_is_noisier_than_a_tenth(tmp_path):
    """On the sphere only rim pixels trace something (lobe directions below the facets hit
    the sphere), so the control variate's noise there cannot move the methods' median error:
    the reference stops, all reliable, with its median noise where it traces still above a
    tenth of hwconv's error (the rule on that median alone would have run on)."""
    ball = ball_scene(tmp_path, spot_map(32))
    out = tmp_path / "traced"
    argv = ["compare", "--scene", str(ball), "--methods", "mirror,hwconv", "--out", str(out)]
    argv += ["--size", "24x24", "--frames", "2", "--warmup", "1", "--param", "trace=true"]
    assert main([*argv, "--param", "kd=0"]) == 0
    report = json.loads((out / "compare.json").read_text())
    reference = report["reference"]
    assert reference["stopped_by"] == "reliable" and report["reliable"]
    hwconv = report["methods"]["hwconv"]["median_relative_error"]
    assert reference["relative_standard_error"] > NOISE_SHARE * hwconv
