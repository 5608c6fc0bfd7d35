"""Issue 40 item 2: a control-variate reference judges each method by the standard error its
own noise, known per pixel, gives the method's median error
(stopping.median_error_uncertainty).

Synthetic cases with known answers, the judgement built on them, and compare on a convex
sphere: nothing is left to sample, so the trace stops at its first judgement.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from envstudio.cli import main
from envstudio.core.env_sampling import LUMINANCE
from envstudio.core.metrics import relative_error
from envstudio.measure.compare import MethodResult, _judge
from envstudio.measure.exact_reference import CheckedError
from envstudio.measure.ground_truth import ConvergenceStatus
from envstudio.measure.reference_runs import ReferenceRun
from envstudio.measure.stopping import (
    CONFIDENCE,
    NOISE_SHARE,
    Judgement,
    control_variate_uncertainty,
    median_error_uncertainty,
)
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
    assert median_error_uncertainty(method, reference, np.zeros(errors.shape), mask) == 0.0


def test_noise_at_every_pixel_gives_the_median_its_asymptotic_standard_error(errors):
    """σ everywhere, errors even over [0, 0.2] (density 5): with s = σ (1 + e) the median's
    variance is sum P (1 - P) / (n f)², sum P (1 - P) = n f s / sqrt(pi) (the integral of
    Phi (1 - Phi) is 1 / sqrt(pi)), so its standard error is sqrt(s / (f n sqrt(pi))): far
    below σ, which the same σ moving every pixel one way would give."""
    method, reference, mask = frames_with_errors(errors)
    sigma = 0.004
    uncertainty = median_error_uncertainty(
        method, reference, np.full(errors.shape, sigma), mask, draws=1024
    )
    s = sigma * (1.0 + np.median(errors))
    assert uncertainty == pytest.approx(np.sqrt(s / (5.0 * errors.size * np.sqrt(np.pi))), rel=0.1)
    assert uncertainty < 0.1 * sigma


@pytest.mark.parametrize("largest", [0.2, 0.02])
def test_the_uncertainty_is_the_median_s_distance_from_the_truth_over_new_references(
    errors, largest
):
    """Half the pixels exact, the rest with noise from 1 % to ``largest``: the bootstrap's
    number from one noisy reference is the root mean square distance of the median error from
    the truth's over 400 references drawn again around the truth (plain relative_error and
    median, apart from the code), bias included: at noise up to 20 % the median error is
    biased by several times its spread, which the bootstrap's copies about the observed one
    repeat."""
    method, truth, mask = frames_with_errors(errors)
    rng = np.random.default_rng(11)
    sigma = np.where(rng.random(errors.shape) < 0.5, 0.0, rng.uniform(0.01, largest, errors.shape))

    def drawn() -> np.ndarray:
        return truth * (1.0 + sigma * rng.standard_normal(errors.shape))[..., None]

    truth_median = np.median(relative_error(method, truth))
    medians = np.array([np.median(relative_error(method, drawn())) for _ in range(400)])
    distance = np.sqrt(np.mean((medians - truth_median) ** 2))
    uncertainty = median_error_uncertainty(method, drawn(), sigma, mask, draws=512)
    assert uncertainty == pytest.approx(distance, rel=0.3)


def test_a_tenth_of_unknown_pixels_moves_the_median_by_their_imbalance(errors):
    """A tenth of the pixels unknown (inf noise), each above or below every other at even
    odds: the median of the rest moves by half their imbalance (standard deviation sqrt(k))
    in ranks of the others (errors even over [0, 0.2]: 0.2 / (n - k) a rank), about the
    median of the rest, which lies off the observed one (the unknown pixels at their values)."""
    method, reference, mask = frames_with_errors(errors)
    noise = np.zeros(errors.shape)
    noise.flat[::10] = np.inf
    unknown = np.isinf(noise)
    uncertainty = median_error_uncertainty(method, reference, noise, mask, draws=1024)
    imbalance = 0.5 * np.sqrt(unknown.sum()) * 0.2 / (errors.size - unknown.sum())
    offset = np.median(errors[~unknown]) - np.median(errors)
    assert uncertainty == pytest.approx(np.hypot(imbalance, offset), rel=0.15)


def test_a_drift_since_half_the_samples_counts_where_the_noise_reads_zero(errors):
    """Nothing noisy (every pixel's noise 0, as where a rarely cut lobe has traced nothing
    yet): the estimate of half the samples 2 % brighter moves the median error by about 2 %
    of its 1.1: that drift, counted CONFIDENCE times, is the uncertainty; none before there is
    a half (inf)."""
    method, reference, mask = frames_with_errors(errors)
    quiet = np.zeros(errors.shape)
    assert control_variate_uncertainty(method, reference, quiet, mask, reference) == 0.0
    half = 1.02 * reference
    drift = np.median(errors) - np.median(np.abs(1.0 + errors - 1.02) / 1.02)
    uncertainty = control_variate_uncertainty(method, reference, quiet, mask, half)
    assert uncertainty == pytest.approx(CONFIDENCE * abs(drift), rel=0.01)
    assert CONFIDENCE == 2.0 and abs(drift) > 0.015
    assert control_variate_uncertainty(method, reference, quiet, mask, None) == np.inf


def test_a_control_variate_counts_the_median_s_standard_error_twice_without_drift(errors):
    """σ at every pixel and no drift: the uncertainty is CONFIDENCE standard errors of the
    median, far below σ, which moving every pixel one way at once would give."""
    method, reference, mask = frames_with_errors(errors)
    noise = np.full(errors.shape, 0.004)
    standard_error = median_error_uncertainty(method, reference, noise, mask)
    uncertainty = control_variate_uncertainty(method, reference, noise, mask, reference)
    assert uncertainty == pytest.approx(CONFIDENCE * standard_error, rel=1e-9)
    assert uncertainty < 0.004 / 2


def test_the_judgement_takes_each_method_s_uncertainty_over_the_median_noise():
    """A control variate's median noise where it traces (2 %) would mark both methods; their
    uncertainties mark only the one whose median's standard error is a tenth of its error."""
    judgement = Judgement(
        batches=8,
        samples=64,
        seconds=1.0,
        noise=0.02,
        errors={"good": 0.05, "close": 0.05},
        uncertainties={"good": 0.001, "close": 0.01},
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


@pytest.mark.parametrize(("checked", "reliable"), [(0.001, True), (0.02, False)])
def test_a_control_variate_s_exact_bound_marks_a_method_its_noise_would_not(
    errors, checked, reliable
):
    """Nothing left to sample (no pixel noise) leaves the exact part's checked error: a
    method whose median error (0.1 here) is under ten times it is marked, with that reason."""
    method, reference, mask = frames_with_errors(errors)
    run = ReferenceRun(
        parameters={"time_limit": 60.0, "max_samples": 8192},
        status=ConvergenceStatus(),
        frames_ms=[1.0],
        total_s=0.001,
        relative_standard_error=0.0,
        resumed_samples=0,
        hdr=reference,
        display=reference,
        stopping_rule="noise",
        stopped_by="reliable",
        exact_error=CheckedError(checked, 2 * checked, 12),
        control_variate=True,
        pixel_noise=np.zeros(errors.shape, np.float32),
        half_hdr=reference,
    )
    result = MethodResult("m", {}, {}, None, None, None, {}, "", method, method)
    assert _judge(result, run, mask, "reference").reliable is reliable
    assert run.unreliable_reason.startswith("the exact reference's checked error (median")
