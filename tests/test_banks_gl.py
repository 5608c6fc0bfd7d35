"""Method banks on the GPU (EGL): the compute-built 3D map against the NumPy one, a constant
environment, a sphere against the brute-force Banks integral, the slice view, bad input."""

import numpy as np
import pytest

from envstudio.engine.session import RenderSession
from envstudio.envmap.conversions import read_cube
from envstudio.methods.banks import lobe as banks
from envstudio.methods.banks.maps import MapSpec, build_cpu, read_map
from envstudio.scene.environment import Environment
from test_bad_input import assert_one_line_error, run_cli
from test_banks import brute_force, smooth_environment
from test_render_gl import render, sphere_geometry, sphere_scene

SIZE = (48, 48)
SMALL = {"map_size": 16, "slices": 16, "bins": 48}


@pytest.fixture
def smooth_session(gl_ctx):
    session = RenderSession(sphere_scene(Environment(smooth_environment(64))), gl_ctx, 64)
    yield session
    session.release()


def test_the_gpu_map_matches_the_numpy_map(smooth_session):
    method = smooth_session.method("banks")
    render(smooth_session, "banks", (8, 8), sharpness=0.9, **SMALL)
    gpu = read_map(method._map)
    spec = MapSpec(16, 16, 48, 0.9)
    cpu = build_cpu(read_cube(smooth_session.gpu_scene.cube), spec, progress=False)
    np.testing.assert_allclose(gpu, cpu, rtol=1e-4, atol=1e-4 * np.abs(cpu).max())
    # a change of s alone reuses the ring table, and still matches
    render(smooth_session, "banks", (8, 8), sharpness=0.5, **SMALL)
    cpu = build_cpu(read_cube(smooth_session.gpu_scene.cube), MapSpec(16, 16, 48, 0.5), False)
    np.testing.assert_allclose(read_map(method._map), cpu, rtol=1e-4, atol=1e-4 * cpu.max())
    assert method.builds == 2


def test_a_constant_environment_reflects_that_constant_per_vertex_and_per_pixel(gl_ctx):
    colour = np.array([0.25, 0.5, 4.0], np.float32)
    image = np.broadcast_to(colour, (32, 64, 3)).copy()
    session = RenderSession(sphere_scene(Environment(image), rings=24), gl_ctx, 32)
    try:
        hit, _, _ = sphere_geometry(session.camera, SIZE)
        inner = hit & np.roll(hit, 2, 0) & np.roll(hit, -2, 0) & np.roll(hit, 2, 1)
        for per_pixel in (False, True):
            out = render(session, "banks", SIZE, per_pixel=per_pixel, kd=0.0, **SMALL)
            np.testing.assert_allclose(out[inner], np.broadcast_to(colour, out[inner].shape), 2e-3)
    finally:
        session.release()


def test_a_sphere_matches_the_brute_force_banks_integral(smooth_session):
    """Per pixel, tangents around Y, mirror Fresnel: the normalised lobe against ∑ f L Ω / ∫ f
    over a 64 × 128 lat-long at every reflector pixel; RMS < 1 %, max < 4 %."""
    s = 0.9
    out = render(smooth_session, "banks", SIZE, sharpness=s, per_pixel=True, **SMALL)
    hit, normal, view = sphere_geometry(smooth_session.camera, SIZE)
    t = np.cross((0.0, 1.0, 0.0), normal)
    length = np.linalg.norm(t, axis=-1)
    ok = hit & (length > 0.05)
    t = t / np.where(ok, length, 1.0)[..., None]
    b = np.sum(view * t, -1)
    image = smooth_environment(64)
    rng = np.random.default_rng(3)
    pixels = np.argwhere(ok)[rng.choice(ok.sum(), 60, replace=False)]
    rel = []
    for i, j in pixels:
        expected = brute_force(image, t[i, j], b[i, j], s) / banks.lobe_integral(b[i, j], s)
        rel.append(np.abs(out[i, j] - expected) / expected)
    rms = np.sqrt(np.mean(np.square(rel)))
    assert rms < 0.01 and np.max(rel) < 0.04, (rms, np.max(rel))


def test_the_slice_view_shows_a_slice_and_per_vertex_differs_from_per_pixel(smooth_session):
    first = render(smooth_session, "banks", (16, 16), view="slice", slice_angle=44.0, **SMALL)
    other = render(smooth_session, "banks", (16, 16), view="slice", slice_angle=120.0, **SMALL)
    assert np.all(np.isfinite(first)) and first.min() > 0 and np.abs(first - other).max() > 0.05
    coarse = dict(SMALL, sharpness=0.99)
    a = render(smooth_session, "banks", SIZE, view="reflector", per_pixel=False, **coarse)
    b = render(smooth_session, "banks", SIZE, per_pixel=True, **coarse)
    assert np.all(np.isfinite(a)) and 0 < np.abs(a - b).max()


def test_bad_input_is_a_one_line_error(capsys, tmp_path):
    out = str(tmp_path / "x.png")
    common = ("render", "--method", "banks", "--size", "8x8", "-o", out)
    status, err = run_cli(capsys, *common, "--param", "sharpness=1")
    assert_one_line_error(status, err, "sharpness=1", "[0, 0.9999]")
    args = ("--param", "tangent_field=uv", "--param", "map_size=8", "--param", "slices=4")
    status, err = run_cli(capsys, *common, "--param", "bins=8", *args)
    assert_one_line_error(status, err, "tangent_field=uv", "no texture coordinates")
