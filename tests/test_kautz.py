"""Method kautz without a GPU: SH bands, the light decomposition, face cameras, seams, CLI."""

import json

import numpy as np
import pytest

from envstudio.cli import main
from envstudio.core import cubemap, latlong
from envstudio.core.sh import project_latlong_sh9, sh9_basis
from envstudio.core.sh_bands import BAND_SETS, a_hat, irradiance, project, sh_basis
from envstudio.core.sh_lights import DiffuseProjector, cap_irradiance, cube_tiles
from envstudio.envmap.dynamic_cube import FACE_AXES, face_view
from envstudio.envmap.mipmaps import edge_jumps
from envstudio.io.images import read_environment, write_image
from envstudio.prefilter import brute_force

RNG = np.random.default_rng(7)


def random_directions(count: int) -> np.ndarray:
    d = RNG.normal(size=(count, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def test_bands_0_to_2_are_seed_000_eq_9():
    d = random_directions(200)
    np.testing.assert_allclose(sh_basis(d, BAND_SETS[9]), sh9_basis(d), atol=1e-14)


def test_basis_up_to_order_8_is_orthonormal():
    h = 256
    Y = sh_basis(latlong.texel_directions(h).reshape(-1, 3), tuple(range(9)))
    w = latlong.texel_solid_angles(h).reshape(-1)
    np.testing.assert_allclose((Y * w[:, None]).T @ Y, np.eye(81), atol=1e-4)


def test_a_hat_matches_ramamoorthi_hanrahan():
    expected = [np.pi, 2 * np.pi / 3, np.pi / 4, 0.0, -np.pi / 24, 0.0, np.pi / 64]
    np.testing.assert_allclose([a_hat(band) for band in range(7)], expected, atol=1e-15)


@pytest.mark.parametrize(("coefficients", "tolerance"), [(9, 1e-4), (25, 4e-4), (49, 4e-4)])
def test_combination_of_basis_functions_comes_back(coefficients, tolerance):
    """Eq. 9's 9 functions to 1e-4 (the midpoint rule's O(h²) error at 6 × 128² texels)."""
    bands = BAND_SETS[coefficients]
    c = RNG.normal(size=(sh_basis(np.array([0.0, 0.0, 1.0]), bands).shape[-1], 3))
    for directions, solid_angles in (
        (latlong.texel_directions(256), latlong.texel_solid_angles(256)),
        (cubemap.texel_directions(128), cubemap.texel_solid_angles(128)),
    ):
        radiance = sh_basis(directions, bands) @ c
        lighting = DiffuseProjector(directions, solid_angles, coefficients).project(radiance)
        np.testing.assert_allclose(lighting.coefficients, c, atol=tolerance)


def test_sh9_projection_agrees_with_core_sh():
    image = RNG.uniform(0.0, 2.0, size=(32, 64, 3))
    lighting = DiffuseProjector.for_latlong(32).project(image)
    np.testing.assert_allclose(lighting.coefficients, project_latlong_sh9(image), atol=1e-12)


@pytest.mark.parametrize(("coefficients", "lights"), [(9, 0), (25, 8), (49, 32)])
def test_constant_environment_has_irradiance_pi_times_l(coefficients, lights):
    L = np.array([0.25, 0.5, 1.5])
    image = np.broadcast_to(L, (256, 512, 3))
    projector = DiffuseProjector.for_latlong(256, coefficients=coefficients, lights=lights)
    lighting = projector.project(image)
    assert len(lighting.lights) == 0, "a constant map has nothing above its mean"
    E = lighting.irradiance(random_directions(500))
    np.testing.assert_allclose(E, np.broadcast_to(np.pi * L, E.shape), rtol=1e-4)


def test_cap_irradiance_matches_a_brute_force_integral():
    h = 512
    d = latlong.texel_directions(h).reshape(-1, 3)
    w = latlong.texel_solid_angles(h).reshape(-1)
    for half_angle in (3.0, 20.0, 50.0):
        inside = d[:, 0] >= np.cos(np.radians(half_angle))  # a cap about +X, on the equator
        moment = np.linalg.norm(w[inside] @ d[inside])  # |V| of the discretised cap
        for theta in (0.0, 70.0, 88.0, 95.0, 110.0):
            n = np.array([np.cos(np.radians(theta)), 0.0, np.sin(np.radians(theta))])
            truth = (np.maximum(d[inside] @ n, 0.0) * w[inside]).sum() / moment
            got = cap_irradiance(np.cos(np.radians(theta)), np.sin(np.radians(half_angle)) ** 2)
            assert got == pytest.approx(truth, abs=2e-3), (half_angle, theta)


def sun_and_sky(height: int = 64) -> np.ndarray:
    """A sky gradient with a 4° sun of 5000 × the sky's radiance, lat-long."""
    d = latlong.texel_directions(height)
    sky = 0.2 + 0.8 * np.clip(d[..., 1:2], 0.0, 1.0) * np.array([0.4, 0.6, 1.0])
    sun = np.array([0.5, 0.3, -0.81])
    disc = (d @ (sun / np.linalg.norm(sun)) > np.cos(np.radians(4.0)))[..., None]
    return sky + disc * np.array([5000.0, 4000.0, 3000.0])


def test_lights_beat_plain_sh_on_a_sun_and_keep_the_energy():
    image = sun_and_sky(128)
    normals = random_directions(400)
    truth = brute_force.irradiance(image, normals)[..., 1]
    plain = DiffuseProjector.for_latlong(128).project(image)
    split = DiffuseProjector.for_latlong(128, coefficients=49, lights=32).project(image)
    plain_error = np.abs(plain.irradiance(normals)[..., 1] - truth) / truth
    split_error = np.abs(split.irradiance(normals)[..., 1] - truth) / truth
    assert plain_error.mean() > 0.05, "the sun makes 9 coefficients ring"
    assert split_error.mean() < 0.01 and split_error.max() < 0.1


def test_tiles_follow_the_cube_face_layout():
    n, per_edge = 16, 4
    tiles = cube_tiles(cubemap.texel_directions(n), per_edge)
    rows, cols = np.meshgrid(np.arange(n) // 4, np.arange(n) // 4, indexing="ij")
    expected = (np.arange(6)[:, None, None] * per_edge + rows) * per_edge + cols
    np.testing.assert_array_equal(tiles, expected)


def test_irradiance_module_function_matches_the_lighting_object():
    image = sun_and_sky(32)
    lighting = DiffuseProjector.for_latlong(32, coefficients=25).project(image)
    normals = random_directions(50)
    np.testing.assert_allclose(
        irradiance(lighting.coefficients, normals, BAND_SETS[25]), lighting.irradiance(normals)
    )
    d = latlong.texel_directions(32)
    np.testing.assert_allclose(
        project(image, d, latlong.texel_solid_angles(32), BAND_SETS[25]), lighting.coefficients
    )


def test_face_cameras_look_through_the_opengl_face_texels():
    for face in range(6):
        view = face_view(face, (0.0, 0.0, 0.0)).astype(np.float64)
        uv = RNG.uniform(0.0, 1.0, size=(20, 2))
        d = cubemap.uv_to_direction(face, uv)
        eye = (view[:3, :3] @ d.T).T  # view space: looking down -z
        ndc = eye[:, :2] / -eye[:, 2:3]
        np.testing.assert_allclose(ndc, 2.0 * uv - 1.0, atol=1e-12)
        assert np.isclose(np.linalg.det(view[:3, :3]), 1.0), "a rotation, not a mirror"
    assert FACE_AXES.shape == (6, 3, 3)


def test_edge_jumps_see_a_seam_and_not_a_smooth_function():
    faces = 1.0 + 0.1 * cubemap.texel_directions(4)
    across, inside = edge_jumps(faces)
    assert len(across) == 12 and max(across.values()) < 0.05 and inside < 0.05, "smooth"
    seamed = faces.copy()
    seamed[4] += 1.0  # +Z offset from its neighbours
    across, _ = edge_jumps(seamed)
    for (f, g), step in across.items():
        assert (step > 0.9) == (4 in (f, g)), (f, g)


def test_sh_command_prints_eq_9_coefficients(tmp_path, capsys):
    image = sun_and_sky(16).astype(np.float32)
    path = tmp_path / "sky.exr"
    write_image(path, image)
    assert main(["sh", "--env", str(path), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    stored = read_environment(path)
    np.testing.assert_allclose(report["coefficients"], project_latlong_sh9(stored), atol=1e-9)
    assert report["l"] == [0, 1, 1, 1, 2, 2, 2, 2, 2]
    assert main(["sh", "--env", str(path), "--lights", "4", "--coefficients", "49", "--check"]) == 0
    text = capsys.readouterr().out
    assert "light  0" in text and "irradiance vs brute force" in text
    assert main(["sh", "--env", str(path), "--lights", "40"]) == 2
