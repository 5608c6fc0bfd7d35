"""Method hwconv on the GPU (EGL): the two-pass convolution against the brute-force Phong
prefilter, a constant environment, uniforms without recompiles, bad input."""

import numpy as np
import pytest

from envstudio.core import latlong
from envstudio.core.colormap import magma
from envstudio.engine.session import RenderSession
from envstudio.errors import ParameterError
from envstudio.io.images import read_image
from envstudio.methods.hwconv.accuracy import (
    MODES,
    error_image_panels,
    format_accuracy,
    run_accuracy,
    write_error_images,
)
from envstudio.prefilter.brute_force import phong
from envstudio.scene.environment import Environment
from test_bad_input import assert_one_line_error, run_cli
from test_render_gl import render, sphere_geometry, sphere_scene

SIZE = (64, 64)
# 64 texels across the disc, 16 of border: faces of 96 texels, enough for N ≥ 20.
MAP = {"map_size": 64, "border": 16}


def smooth_environment(height: int = 64) -> np.ndarray:
    """(h, 2h, 3) float32: low-order polynomials of the direction, all positive."""
    x, y, z = np.moveaxis(latlong.texel_directions(height), -1, 0)
    channels = [1.5 + 0.5 * x + 0.3 * y - 0.4 * z + 0.3 * x * y, 1.2 - 0.3 * x + 0.5 * z * z]
    channels.append(1.0 + 0.2 * y + 0.4 * x * z)
    return np.stack(channels, -1).astype(np.float32)


@pytest.fixture
def smooth_session(gl_ctx):
    session = RenderSession(
        sphere_scene(Environment(smooth_environment())), ctx=gl_ctx, cube_size=64
    )
    yield session
    session.release()


def test_two_pass_matches_the_brute_force_phong_prefilter_on_a_smooth_map(smooth_session):
    """Over every pixel of a mirror-Fresnel sphere, both paraboloid faces and the rim:
    relative error against seed 000 eq. 7's normalised lobe, RMS < 0.5 %, max < 2 %
    (measured 0.33 % / 1.4 % at N = 20, 0.11 % / 1.25 % at N = 100); one pass is worse."""
    image = smooth_environment()
    hit, normal, view = sphere_geometry(smooth_session.camera, SIZE)
    reflection = 2.0 * np.sum(normal * view, -1, keepdims=True) * normal - view
    for exponent in (20.0, 100.0):
        expected = phong(image, reflection[hit], exponent)
        errors = {}
        for one_pass in (False, True):
            out = render(
                smooth_session, "hwconv", SIZE, phong_exponent=exponent, one_pass=one_pass, **MAP
            )
            rel = np.abs(out[hit] - expected) / expected
            errors[one_pass] = np.sqrt(np.mean(rel**2))
            if not one_pass:
                assert errors[False] < 0.005 and rel.max() < 0.02, (exponent, rel.max())
        assert errors[False] <= errors[True], errors


def test_a_constant_environment_gives_the_constant_in_every_map_borders_included(gl_ctx):
    colour = np.array([0.25, 0.5, 4.0], np.float32)
    session = RenderSession(
        sphere_scene(Environment.constant(colour, height=32)), ctx=gl_ctx, cube_size=32
    )
    hit, _, _ = sphere_geometry(session.camera, SIZE)
    out = render(session, "hwconv", SIZE, phong_exponent=30.0, **MAP)
    np.testing.assert_allclose(out[hit], np.broadcast_to(colour, out[hit].shape), rtol=1e-5)
    maps = session.method("hwconv").convolution.maps
    for name in ("small", "large", "blended"):
        faces = maps[name].read()  # (2, n, n, 3), the border's texels included
        np.testing.assert_allclose(faces, np.broadcast_to(colour, faces.shape), rtol=1e-5)
    session.release()


def test_n_and_epsilon_change_uniforms_and_refilter_without_recompiling(smooth_session):
    method = smooth_session.method("hwconv")
    first = render(smooth_session, "hwconv", SIZE, phong_exponent=50.0, epsilon=0.1, **MAP)
    programs = smooth_session.programs.compile_count
    refilters = method.refilters
    second = render(smooth_session, "hwconv", SIZE, phong_exponent=200.0)
    third = render(smooth_session, "hwconv", SIZE, epsilon=0.02)
    assert smooth_session.programs.compile_count == programs
    assert method.refilters == refilters + 2
    assert not np.allclose(first, second) and not np.allclose(second, third)
    render(smooth_session, "hwconv", SIZE)  # nothing changed: no refilter
    assert method.refilters == refilters + 2
    render(smooth_session, "hwconv", SIZE, refilter_every_frame=True)
    render(smooth_session, "hwconv", SIZE)
    assert method.refilters == refilters + 4
    assert smooth_session.programs.compile_count == programs


def test_the_views_show_the_maps_front_left_back_right(smooth_session):
    """view=small|large|blended draws the face pair as the frame; front +Z is bluer."""
    for view in ("small", "large", "blended"):
        out = render(smooth_session, "hwconv", (64, 32), view=view, phong_exponent=50.0, **MAP)
        # Red channel 1.5 + 0.5x + 0.3y − 0.4z: the back face (z < 0) is redder.
        assert out[16, 48, 0] > out[16, 16, 0] + 0.3, view


def test_a_border_too_small_is_a_one_line_error_naming_the_minimum(smooth_session):
    method = smooth_session.method("hwconv")
    method.values.update({"phong_exponent": 10.0, "map_size": 64, "border": 8})
    with pytest.raises(ParameterError, match=r"^border=8: expected an integer >= 17 "):
        smooth_session.render_offscreen(method, (8, 8))


def test_a_map_beyond_the_texture_limit_is_refused_before_allocating(smooth_session):
    method = smooth_session.method("hwconv")
    limit = int(smooth_session.ctx.info["GL_MAX_TEXTURE_SIZE"])
    method.values.update({"map_size": limit, "border": 64})
    with pytest.raises(ParameterError, match=rf"^map_size={limit}: expected an integer in \[8, "):
        smooth_session.render_offscreen(method, (8, 8))


@pytest.mark.parametrize(
    ("param", "fragment"),
    [
        ("phong_exponent=0", "phong_exponent=0: expected a number in [1, 10000]"),
        ("epsilon=1", "epsilon=1: expected a number in [0.001, 0.99]"),
        ("border=4", "border=4: expected an integer >= "),
    ],
)
def test_bad_values_from_the_command_line_are_one_line(capsys, tmp_path, param, fragment):
    out = str(tmp_path / "out.png")
    argv = ["render", "--method", "hwconv", "--size", "16x16", "--param", param, "-o", out]
    assert_one_line_error(*run_cli(capsys, *argv), fragment)


def test_exact_kernel_beats_two_maps_which_beat_one_on_a_sharp_map(gl_ctx):
    """A bright 26° cap: RMS relative error over the sphere against the brute force at
    N = 20 (measured: exact 3.6 %, two maps 6.7 %, one pass 12.4 %)."""
    d = latlong.texel_directions(64)
    axis = np.array([0.5, 0.6, 0.62]) / np.linalg.norm([0.5, 0.6, 0.62])
    image = (0.2 + 5.0 * (d @ axis > 0.9)[..., None] * np.ones(3)).astype(np.float32)
    session = RenderSession(sphere_scene(Environment(image)), ctx=gl_ctx, cube_size=64)
    hit, normal, view = sphere_geometry(session.camera, SIZE)
    reflection = 2.0 * np.sum(normal * view, -1, keepdims=True) * normal - view
    expected = phong(image, reflection[hit], 20.0)
    rms = {}
    for name, kernel, one_pass in (
        ("exact", "exact", False),
        ("two_maps", "two_maps", False),
        ("one_pass", "two_maps", True),
    ):
        out = render(
            session,
            "hwconv",
            SIZE,
            phong_exponent=20.0,
            kernel=kernel,
            one_pass=one_pass,
            map_size=64,
            border=24,
        )
        rms[name] = np.sqrt(np.mean((np.abs(out[hit] - expected) / expected) ** 2))
    session.release()
    assert rms["exact"] < 0.05 and rms["exact"] < rms["two_maps"] < rms["one_pass"], rms


def test_accuracy_bench_reads_back_what_the_reflector_shows(smooth_session):
    """``bench --hwconv-accuracy``'s lookup of the read-back maps reproduces the sphere test's
    numbers on the smooth map (measured 0.31 % / 1.4 % two maps, 0.69 % one pass at N = 20)."""
    smooth_session.method("hwconv").values.update({"map_size": 64, "border": 8})
    report = run_accuracy(smooth_session, [20.0], 512, progress=False)
    row = report["rows"][0]
    assert report["map"]["border"] == 21  # raised to the exact kernel's reach at N = 20
    assert row["two_pass"]["rms"] < 0.005 and row["two_pass"]["max"] < 0.02, row
    assert row["exact"]["rms"] < row["two_pass"]["rms"] < row["one_pass"]["rms"], row
    assert "| 20 | 0." in format_accuracy(report)


def test_accuracy_error_images_encode_the_tables_errors(smooth_session, tmp_path):
    """One PNG per exponent beside the JSON; decoding each panel's colours through the
    colour map gives back the table's maximum (within the 8-bit quantisation), and
    an error of zero is the colour map's zero colour."""
    smooth_session.method("hwconv").values.update({"map_size": 32, "border": 8})
    errors: dict = {}
    report = run_accuracy(smooth_session, [20.0], 256, progress=False, errors=errors)
    scale, face = 0.05, 48
    (path,) = write_error_images(report, errors, tmp_path / "acc.json", scale=scale, face=face)
    assert path == tmp_path / "acc.error_N20.png"
    image = read_image(path)[..., :3]
    ramp = magma(np.linspace(0.0, 1.0, 2048))
    row = report["rows"][0]
    for mode, (top, left, size) in error_image_panels(face).items():
        pixels = np.concatenate(
            [image[top : top + size, x : x + size] for x in (left, left + size + 4)], axis=1
        ).reshape(-1, 3)
        on_ramp = np.linalg.norm(pixels - 1.0, axis=-1) > 1e-3  # not the white outside
        nearest = np.argmin(np.linalg.norm(pixels[on_ramp, None] - ramp[None], axis=-1), -1)
        decoded = nearest.max() / (len(ramp) - 1) * scale
        assert decoded == pytest.approx(min(row[mode]["max"], scale), abs=0.01 * scale), mode
    zero = {(20.0, mode): np.zeros_like(e) for (_, mode), e in errors.items()}
    (path,) = write_error_images(report, zero, tmp_path / "zero.json", scale=scale, face=face)
    top, left, size = error_image_panels(face)[next(iter(MODES))]
    centre = read_image(path)[top + size // 2, left + size // 2, :3]
    assert np.abs(centre - magma(0.0)).max() <= 0.5 / 255 + 1e-6


def test_accuracy_bench_refuses_a_scene_with_local_objects(capsys):
    argv = ["bench", "--methods", "hwconv", "--hwconv-accuracy", "--scene", "room"]
    assert_one_line_error(*run_cli(capsys, *argv), "expected a scene without local objects")
