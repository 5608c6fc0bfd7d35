"""Issue 40: the exact reference of the untraced environment-map model (``model=phong``).

Against an independent NumPy brute force (every sample, not a few), a constant environment
(the constant times the albedo), the Monte Carlo reference within its noise, and through
``compare`` (deterministic, reliable, seconds).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from envstudio.cli import main
from envstudio.core.latlong import texel_directions, texel_solid_angles
from envstudio.engine.session import RenderSession
from envstudio.io.images import read_image
from envstudio.io.scene_setup import build_scene
from envstudio.measure.exact_reference import (
    brute_force_radiance,
    eq8_radiance,
    exact_frame,
    exact_radiance,
)
from envstudio.measure.ground_truth import PairedEstimates
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene
from envstudio.scene.primitives import torus_knot
from scene_files import ball_scene

FRESNEL = np.array([0.9, 0.5, 0.2])
KD = np.array([0.2, 0.4, 0.6])


def spot_map(height: int = 16) -> np.ndarray:
    """(h, 2h, 3) a smooth sky with one bright, coloured spot."""
    d = texel_directions(height)
    sky = np.stack([0.4 + 0.3 * d[..., 1], 0.5 + 0.2 * d[..., 0], 0.8 - 0.3 * d[..., 2]], -1)
    sky += (
        np.array([6.0, 3.0, 1.0])
        * np.exp(-20.0 * np.sum((d - [0.3, 0.5, 0.8]) ** 2, -1))[..., None]
    )
    return np.maximum(sky, 0.0).astype(np.float32)


def random_frames(count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(count, 3) unit normals and views, every view within 85° of its normal."""
    rng = np.random.default_rng(seed)
    n = rng.normal(size=(count, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    v = rng.normal(size=(count, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v = np.where((np.einsum("sk,sk->s", n, v) < 0.1)[:, None], -v + 0.3 * n, v)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return n, v


def numpy_eq8(radiance, normals, views, fresnel, kd, exponent, split=8) -> np.ndarray:
    """Seed 000 eq. 8 integrated over the map as a function constant over each texel, written
    here from the formula alone: a plain sum over every texel cut into ``split``² parts."""
    fine = np.repeat(np.repeat(radiance, split, axis=0), split, axis=1)
    h, w = fine.shape[:2]
    directions = texel_directions(h, w).reshape(-1, 3)
    weighted = fine.reshape(-1, 3).astype(np.float64) * texel_solid_angles(h, w).reshape(-1, 1)
    cos_nv = np.einsum("sk,sk->s", normals, views)
    r = 2.0 * cos_nv[:, None] * normals - views
    f = fresnel + (1.0 - fresnel) * ((1.0 - np.clip(cos_nv, 0, 1)) ** 5)[:, None]
    diffuse = np.maximum(normals @ directions.T, 0.0) / np.pi @ weighted
    glossy = (exponent + 1) / (2 * np.pi) * np.maximum(r @ directions.T, 0.0) ** exponent @ weighted
    out = (1.0 - f) * kd * diffuse + f * glossy
    return np.where((cos_nv > 0)[:, None], out, 0.0)


@pytest.mark.parametrize("exponent", [1.0, 20.0, 300.0])
def test_every_sample_matches_an_independent_numpy_sum(exponent):
    radiance = spot_map()
    normals, views = random_frames(400, seed=int(exponent))
    exact = eq8_radiance(radiance, normals, views, FRESNEL, KD, exponent)
    expected = numpy_eq8(radiance, normals, views, FRESNEL, KD, exponent)
    scale = expected.max(axis=1)
    assert np.all(scale > 0)
    relative = np.abs(exact - expected).max(axis=1) / scale
    assert relative.max() < 1e-2, relative.max()
    assert relative.mean() < 1e-3, relative.mean()


def test_a_constant_environment_gives_the_constant_times_the_albedo():
    radiance = np.full((16, 32, 3), 0.7, np.float32)
    normals, views = random_frames(300, seed=5)
    for exponent in (1.0, 50.0, 2000.0):
        exact = eq8_radiance(radiance, normals, views, FRESNEL, KD, exponent)
        cos = np.clip(np.einsum("sk,sk->s", normals, views), 0, 1)
        f = FRESNEL + (1 - FRESNEL) * ((1 - cos) ** 5)[:, None]
        np.testing.assert_allclose(exact, 0.7 * ((1 - f) * KD + f), rtol=2e-4)


def test_a_grey_fresnel_and_kd_given_as_numbers_are_their_rgb_triples():
    radiance = spot_map()
    normals, views = random_frames(40, seed=3)
    for fresnel, kd in ((0.5, 0.3), (0.5, [0.3] * 3), ([0.5] * 3, 0.3)):
        values = {"model": "phong", "fresnel": fresnel, "kd": kd, "phong_exponent": 20.0}
        triples = values | {"fresnel": [0.5] * 3, "kd": [0.3] * 3}
        np.testing.assert_array_equal(
            exact_radiance(radiance, normals, views, values),
            exact_radiance(radiance, normals, views, triples),
        )
        np.testing.assert_array_equal(
            brute_force_radiance(radiance, normals[:4], views[:4], values),
            brute_force_radiance(radiance, normals[:4], views[:4], triples),
        )


def test_a_sample_facing_away_reflects_nothing():
    radiance = spot_map()
    normals, views = random_frames(50, seed=9)
    assert not eq8_radiance(radiance, normals, -views, FRESNEL, KD, 20.0).any()


@pytest.fixture
def ball(tmp_path):
    """A glossy sphere under the spot sky (as test_compare's small scene)."""
    return ball_scene(tmp_path, spot_map(32))


def test_the_frame_is_the_numpy_sum_box_filtered_over_each_pixel_s_covered_samples(ball):
    session = RenderSession(build_scene(str(ball)))
    try:
        normals, views = session.renderer.reflector_surface(
            session.gpu_scene, session.camera, (48, 48)
        )
        camera = session.camera.position
    finally:
        session.release()
    covered = np.linalg.norm(normals, axis=-1) > 0.5
    assert 0.2 < covered.mean() < 0.9
    # the surface pass: a sphere's shading normal points away from its centre, within the
    # tessellation's few degrees, and the view is a unit vector towards the camera
    n, v = normals[covered], views[covered]
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-5)
    assert np.einsum("sk,sk->s", n, v).min() > -1e-3  # the seen side of a convex ball
    assert (np.einsum("sk,k->s", v, camera / np.linalg.norm(camera)) > 0.5).all()
    values = {"fresnel": FRESNEL, "kd": KD, "phong_exponent": 40.0}
    radiance = read_image(ball.parent / "sky.exr")[..., :3]
    frame = exact_frame(normals, views, radiance, values, ssaa=3)
    fine = np.zeros((48, 48, 3))
    fine[covered] = numpy_eq8(radiance, n.astype(np.float64), v, FRESNEL, KD, 40.0, split=6)
    count = covered.reshape(16, 3, 16, 3).sum(axis=(1, 3))
    expected = fine.reshape(16, 3, 16, 3, 3).sum(axis=(1, 3)) / np.maximum(count, 1)[..., None]
    np.testing.assert_array_equal(frame.mask, count > 0)
    scale = expected[frame.mask].max()
    assert np.abs(frame.hdr - expected)[frame.mask].max() < 2e-3 * scale
    assert 0 <= frame.error.median <= frame.error.largest < 1e-2 and frame.error.samples > 8


def test_compare_against_the_exact_reference_is_deterministic_and_reliable(ball, tmp_path):
    """trace=false: the untraced model is the reference, evaluated, not sampled: two runs
    give the same numbers, every row is reliable, and the report says exact."""
    reports = []
    for run in ("a", "b"):
        out = tmp_path / run
        argv = ["compare", "--scene", str(ball), "--methods", "mirror,hwconv", "--out", str(out)]
        argv += ["--size", "24x24", "--frames", "2", "--warmup", "1", "--param", "trace=false"]
        assert main(argv) == 0
        reports.append(json.loads((out / "compare.json").read_text()))
    first, second = reports
    assert first["reference"]["stopped_by"] == "exact" and first["reliable"]
    assert first["reference"]["exact_error"]["largest"] < 1e-2
    for name in ("mirror", "hwconv"):
        a, b = first["methods"][name], second["methods"][name]
        assert a["median_relative_error"] == b["median_relative_error"] > 0
    assert "exact: the untraced model" in (tmp_path / "a" / "compare.md").read_text()


def test_the_exact_reference_agrees_with_the_monte_carlo_one_within_its_noise(ball, tmp_path):
    out = {}
    for kind in ("exact", "montecarlo"):
        out[kind] = tmp_path / kind
        argv = ["compare", "--scene", str(ball), "--methods", "mirror", "--out", str(out[kind])]
        argv += ["--size", "24x24", "--frames", "2", "--warmup", "1", "--param", "trace=false"]
        argv += ["--reference", kind, "--param", "max_samples=512", "--strict"]
        assert main(argv) == 0
    exact = read_image(out["exact"] / "reference.exr")
    sampled = read_image(out["montecarlo"] / "reference.exr")
    noise = json.loads((out["montecarlo"] / "compare.json").read_text())["reference"]
    session = RenderSession(build_scene(str(ball)))
    try:
        normals, _ = session.renderer.reflector_surface(session.gpu_scene, session.camera, (96, 96))
    finally:
        session.release()
    # the pixels wholly on the ball (the rim's pixels are partly covered in both, each by its
    # own footprint points: the rasterised 4 × 4 and the traced random ones)
    core = (np.linalg.norm(normals, axis=-1) > 0.5).reshape(24, 4, 24, 4).all(axis=(1, 3))
    luminance = np.array([0.2126, 0.7152, 0.0722])
    relative = (exact - sampled) @ luminance / (sampled @ luminance + 1e-9)
    # pixel by pixel within a few of the Monte Carlo reference's standard errors; on the mean
    # over the ball's interior (hundreds of pixels) the sampled one's noise averages out
    assert np.median(np.abs(relative[core])) < 2.0 * noise["relative_standard_error"]
    assert abs(relative[core].mean()) < 0.5 * noise["relative_standard_error"]


def knot_scene() -> Scene:
    """The self-occluding (2, 3) torus knot under the spot sky (tests/test_mitsuba_gl.py's)."""
    camera = OrbitCamera(azimuth=30.0, elevation=25.0, distance=2.6, fov_y=45.0)
    knot = Node("knot", torus_knot().fitted(1.0))
    return Scene(Environment(spot_map(32)), [knot], camera, "knot")


def test_the_control_variate_is_the_traced_estimate_with_far_less_noise_on_the_knot():
    """T − β (U − exact): the same expectation as the plain traced estimate T (per pixel,
    their difference is within the noise), and on the knot, where the traced and untraced
    estimates of the same samples vary together, a fraction of T's noise."""
    session = RenderSession(knot_scene())
    try:
        reference = session.method("reference")
        reference.values.update(
            {"trace": True, "untraced_too": True, "sequence": "random", "adaptive": False}
        )
        reference.values.update({"samples": 4, "max_samples": 65536, "tolerance": 1e-5})
        reference.values.update({"fresnel": 0.9, "kd": 0.1, "phong_exponent": 20.0})
        for _ in range(16):
            session.render_offscreen(reference, (24, 24))
        paired = reference.paired()
        normals, views = session.renderer.reflector_surface(
            session.gpu_scene, session.camera, (96, 96)
        )
        radiance = session.scene.environment.radiance
        exact = exact_frame(normals, views, radiance, reference.values.as_dict(), 4)
    finally:
        session.release()
    controlled, controlled_error = paired.controlled(exact.hdr)
    whole = (np.linalg.norm(normals, axis=-1) > 0.5).reshape(24, 4, 24, 4).all(axis=(1, 3))
    luminance = np.array([0.2126, 0.7152, 0.0722])
    lit = whole & ((paired.traced @ luminance) > 0)
    assert lit.sum() > 100
    combined = np.hypot(paired.traced_error @ luminance, controlled_error @ luminance)
    z = ((controlled - paired.traced) @ luminance)[lit] / combined[lit]
    assert np.median(np.abs(z)) < 1.5, np.median(np.abs(z))
    plain = np.median((paired.traced_error @ luminance)[lit] / (paired.traced @ luminance)[lit])
    control = np.median((controlled_error @ luminance)[lit] / (controlled @ luminance)[lit])
    assert control < 0.5 * plain, (control, plain)


def test_the_control_is_never_noisier_than_the_plain_estimate():
    """PairedEstimates.controlled on synthetic batches: β is Cov(T, U) / Var(U) per pixel,
    its error the spread the formula promises, never above T's, whatever the correlation."""
    rng = np.random.default_rng(3)
    batches, pixels = 4000, 5
    correlation = np.array([1.0, 0.9, 0.5, 0.0, -0.5])
    u = rng.normal(size=(batches, pixels))
    t = correlation * u + np.sqrt(1 - correlation**2) * rng.normal(size=(batches, pixels)) + 3.0
    u += 2.0

    def errors(samples):  # (1, pixels, 3): the standard error of the mean, every channel
        return np.repeat((samples.std(axis=0, ddof=1) / np.sqrt(batches))[None, :, None], 3, -1)

    paired = PairedEstimates(
        traced=np.repeat(t.mean(axis=0)[None, :, None], 3, -1),
        traced_error=errors(t),
        untraced=np.repeat(u.mean(axis=0)[None, :, None], 3, -1),
        untraced_error=errors(u),
        difference_error=errors(t - u),
    )
    estimate, error = paired.controlled(np.full((1, pixels, 3), 2.0))
    plain = paired.traced_error[0, :, 0]
    expected = plain * np.sqrt(1 - np.clip(correlation, 0, None) ** 2)
    np.testing.assert_allclose(error[0, :, 0], expected, atol=0.05 * plain.max())
    assert np.all(error[0, :, 0] <= plain + 1e-9)
    assert np.all(np.abs(estimate[0, :, 0] - 3.0) < 4 * np.maximum(error[0, :, 0], 1e-6))


def test_compare_of_a_traced_sphere_uses_the_control_variate_in_seconds(ball, tmp_path):
    out = tmp_path / "traced"
    argv = ["compare", "--scene", str(ball), "--methods", "mirror,hwconv", "--out", str(out)]
    argv += ["--size", "24x24", "--frames", "2", "--warmup", "1", "--param", "trace=true"]
    assert main(argv) == 0
    report = json.loads((out / "compare.json").read_text())
    assert report["reliable"] and report["reference"]["stopped_by"] == "reliable"
    assert report["untraced_references"]["phong"]["exact_error"]["largest"] < 1e-2
    assert "control variate" in (out / "compare.md").read_text()
