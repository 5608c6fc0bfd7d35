"""Sphere parameterizations and CPU resampling (no GL): round trips, solid angles, known values."""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.core import cubemap, latlong, paraboloid, resample, spheremap

FOUR_PI = 4.0 * np.pi


def fibonacci_directions(count: int) -> np.ndarray:
    """(count, 3) unit directions spread evenly over the sphere (golden-angle spiral)."""
    i = np.arange(count) + 0.5
    y = 1.0 - 2.0 * i / count
    phi = np.pi * (3.0 - np.sqrt(5.0)) * i
    r = np.sqrt(1.0 - y * y)
    return np.stack([r * np.cos(phi), y, r * np.sin(phi)], axis=-1)


def smooth_radiance(d: np.ndarray) -> np.ndarray:
    """A positive RGB field, a low-order polynomial of the direction."""
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return np.stack(
        [1.0 + 0.5 * x + 0.2 * y * z, 1.0 + 0.3 * z * z - 0.2 * y, 0.6 + 0.1 * x * y], -1
    )


DIRECTIONS = fibonacci_directions(100_000)


def test_latlong_round_trip():
    back = latlong.uv_to_direction(latlong.direction_to_uv(DIRECTIONS))
    np.testing.assert_allclose(back, DIRECTIONS, atol=1e-12)


def test_cube_round_trip():
    face, uv = cubemap.direction_to_face_uv(DIRECTIONS)
    assert set(np.unique(face)) == set(range(6))
    assert uv.min() >= 0.0 and uv.max() <= 1.0
    np.testing.assert_allclose(cubemap.face_uv_to_direction(face, uv), DIRECTIONS, atol=1e-12)


@pytest.mark.parametrize(("size", "border"), [(64, 0), (64, 2), (33, 1.5)])
def test_paraboloid_round_trip(size, border):
    face, uv = paraboloid.direction_to_uv(DIRECTIONS, size, border)
    np.testing.assert_array_equal(face, np.where(DIRECTIONS[:, 2] >= 0, 0, 1))
    # The unit disc spans the central n - 2B texels.
    radius = np.linalg.norm(uv - 0.5, axis=-1)
    assert radius.max() <= 0.5 * (size - 2 * border) / size + 1e-12
    back = paraboloid.uv_to_direction(face, uv, size, border)
    np.testing.assert_allclose(back, DIRECTIONS, atol=1e-12)


def test_spheremap_round_trip_away_from_the_singular_direction():
    angle_from_minus_z = np.arccos(np.clip(-DIRECTIONS[:, 2], -1.0, 1.0))
    d = DIRECTIONS[angle_from_minus_z > 1e-3]
    assert len(d) > 99_990
    back = spheremap.uv_to_direction(spheremap.direction_to_uv(d))
    np.testing.assert_allclose(back, d, atol=1e-9)


def test_texel_uv_round_trips():
    """Texel centre -> direction -> uv lands back on the centre, for every parameterization."""
    n = 16
    centres = (np.arange(n) + 0.5) / n
    grid = np.stack(np.meshgrid(centres, centres), axis=-1)
    face, uv = cubemap.direction_to_uv(cubemap.texel_directions(n))
    np.testing.assert_array_equal(face, np.broadcast_to(np.arange(6)[:, None, None], (6, n, n)))
    np.testing.assert_allclose(uv, np.broadcast_to(grid, (6, n, n, 2)), atol=1e-12)
    face, uv = paraboloid.direction_to_uv(paraboloid.texel_directions(n, 1), n, 1)
    inside = np.linalg.norm(2.0 * grid - 1.0, axis=-1) * n / (n - 2) < 1.0
    for f in range(2):
        assert np.all(face[f][inside] == f)
        np.testing.assert_allclose(uv[f][inside], grid[inside], atol=1e-12)
    uv = latlong.direction_to_uv(latlong.texel_directions(n, 2 * n))
    grid2 = np.stack(np.meshgrid((np.arange(2 * n) + 0.5) / (2 * n), centres), axis=-1)
    np.testing.assert_allclose(uv, grid2, atol=1e-12)
    disc = np.linalg.norm(2.0 * grid - 1.0, axis=-1) < 1.0
    uv = spheremap.direction_to_uv(spheremap.texel_directions(n))
    np.testing.assert_allclose(uv[disc], grid[disc], atol=1e-9)


def test_solid_angles_sum_to_four_pi():
    assert latlong.texel_solid_angles(37, 70).sum() == pytest.approx(FOUR_PI, abs=1e-10)
    assert cubemap.texel_solid_angles(17).sum() == pytest.approx(FOUR_PI, abs=1e-10)
    for size, border in [(16, 0), (16, 1), (31, 2.5)]:
        total = paraboloid.texel_solid_angles(size, border).sum()
        assert total == pytest.approx(FOUR_PI, abs=1e-10)
    for size in (1, 2, 15, 64):
        assert spheremap.texel_solid_angles(size).sum() == pytest.approx(FOUR_PI, abs=1e-10)


def _integrate(jacobian, n: int, sub: int) -> np.ndarray:
    """Midpoint rule with sub x sub points per texel of an n x n grid over [0, 1]^2."""
    x = (np.arange(n * sub) + 0.5) / (n * sub)
    s, t = np.meshgrid(x, x)
    return jacobian(s, t).reshape(n, sub, n, sub).sum(axis=(1, 3)) / (n * sub) ** 2


def test_solid_angles_match_a_numerical_integral_of_the_jacobian():
    """The closed forms against brute-force integration of each map's area element."""
    n, sub = 6, 200

    def cube_jacobian(s, t):
        a, b = 2.0 * s - 1.0, 2.0 * t - 1.0
        return 4.0 / (1.0 + a * a + b * b) ** 1.5

    numeric = _integrate(cube_jacobian, n, sub)
    np.testing.assert_allclose(cubemap.texel_solid_angles(n)[3], numeric, rtol=1e-5)

    border = 1
    scale = n / (n - 2 * border)

    def paraboloid_jacobian(s, t):
        r2 = ((2.0 * s - 1.0) ** 2 + (2.0 * t - 1.0) ** 2) * scale**2
        return np.where(r2 <= 1.0, 4.0 / (1.0 + r2) ** 2, 0.0) * (2.0 * scale) ** 2

    numeric = _integrate(paraboloid_jacobian, n, sub)
    exact = paraboloid.texel_solid_angles(n, border)
    # Rim texels carry the midpoint rule's O(1/sub) error of the disc's edge.
    np.testing.assert_allclose(exact[1], numeric, atol=2e-4 * exact.max())

    def spheremap_jacobian(s, t):
        inside = (2.0 * s - 1.0) ** 2 + (2.0 * t - 1.0) ** 2 <= 1.0
        return np.where(inside, 16.0, 0.0)

    numeric = _integrate(spheremap_jacobian, n, sub)
    exact = spheremap.texel_solid_angles(n)
    np.testing.assert_allclose(exact, numeric, atol=2e-4 * exact.max())
    assert spheremap.texel_solid_angles(8)[0, 0] == 0.0  # a corner texel outside the disc

    def latlong_jacobian(s, t):
        return 2.0 * np.pi**2 * np.sin(np.pi * t)

    numeric = _integrate(latlong_jacobian, n, sub)
    np.testing.assert_allclose(latlong.texel_solid_angles(n, n), numeric, rtol=1e-5)


def test_latlong_known_values():
    uv = latlong.direction_to_uv([[0, 0, -1], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]])
    np.testing.assert_allclose(uv[:3], [[0.5, 0.5], [0.75, 0.5], [0.25, 0.5]], atol=1e-15)
    np.testing.assert_allclose(uv[3:, 1], [0.0, 1.0], atol=1e-15)
    np.testing.assert_allclose(latlong.uv_to_direction([0.0, 0.5]), [0, 0, 1], atol=1e-15)
    # Row 0 of the image is next to +Y.
    assert latlong.texel_directions(8)[0, :, 1].min() > 0.9


def test_cube_known_values():
    axes = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])
    face, uv = cubemap.direction_to_uv(axes)
    np.testing.assert_array_equal(face, np.arange(6))
    np.testing.assert_allclose(uv, 0.5)
    # The OpenGL table: on +X, s grows towards -z and t towards -y; on +Y, t grows towards +z.
    d = cubemap.uv_to_direction([0, 0, 2], [[1.0, 0.5], [0.5, 1.0], [0.5, 1.0]])
    s2 = np.sqrt(0.5)
    np.testing.assert_allclose(d, [[s2, 0, -s2], [s2, -s2, 0], [0, s2, s2]], atol=1e-15)
    assert cubemap.FACE_NAMES == ("+X", "-X", "+Y", "-Y", "+Z", "-Z")


def test_cube_cross_layout_is_continuous():
    """Neighbouring pixels across every shared edge of the drawn cross are neighbours on the
    sphere, and cross_to_faces inverts faces_to_cross."""
    n = 16
    dirs = cubemap.texel_directions(n)
    cross = cubemap.faces_to_cross(dirs)
    assert cross.shape == (3 * n, 4 * n, 3)
    np.testing.assert_array_equal(cubemap.cross_to_faces(cross), dirs)
    texel = 2.0 / n  # about a texel's angle at a face edge, where texels are largest
    row = cross[n : 2 * n]  # -X +Z +X -Z, continuous across 3 inner edges and the wrap
    steps = np.linalg.norm(np.diff(np.concatenate([row, row[:, :1]], axis=1), axis=1), axis=-1)
    assert steps.max() < texel
    column = cross[:, n : 2 * n]  # +Y over +Z over -Y
    steps = np.linalg.norm(np.diff(column, axis=0), axis=-1)
    assert steps.max() < texel


def test_paraboloid_known_values():
    n, b = 32, 2
    face, uv = paraboloid.direction_to_uv([[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, 1, 0]], n, b)
    np.testing.assert_array_equal(face, [0, 1, 0, 0])
    rim = 0.5 + 0.5 * (n - 2 * b) / n
    np.testing.assert_allclose(uv, [[0.5, 0.5], [0.5, 0.5], [rim, 0.5], [0.5, rim]])
    # Border texels continue past the rim onto the other hemisphere.
    assert paraboloid.texel_directions(n, b)[0, n // 2, -1, 2] < 0.0
    assert paraboloid.texel_solid_angles(n, b)[:, n // 2, -1].max() == 0.0


def test_spheremap_known_values():
    r = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, -1]])
    uv = spheremap.direction_to_uv(r)
    edge = 0.5 + 0.5 / np.sqrt(2.0)
    np.testing.assert_allclose(uv, [[0.5, 0.5], [edge, 0.5], [0.5, edge], [0.5, 0.0]])
    # Every point on or outside the rim is the singular direction.
    np.testing.assert_allclose(
        spheremap.uv_to_direction([[1.0, 0.5], [0.0, 0.0]]), [[0, 0, -1]] * 2
    )
    # Equal area: every texel wholly inside the disc subtends 16 / n^2.
    sa = spheremap.texel_solid_angles(16)
    assert sa[8, 8] == pytest.approx(16.0 / 256.0, rel=1e-12)


@pytest.mark.parametrize(
    "call",
    [
        lambda: latlong.direction_to_uv(np.zeros((4, 2))),
        lambda: cubemap.uv_to_direction(6, [0.5, 0.5]),
        lambda: paraboloid.texel_directions(8, 4),
        lambda: spheremap.view_rotation_matrix(np.ones((3, 3))),
        lambda: cubemap.faces_to_cross(np.zeros((5, 4, 4))),
        lambda: resample.latlong_to_cube(np.zeros((4, 8)), 4),
    ],
)
def test_bad_shapes_are_rejected(call):
    with pytest.raises(ValueError):
        call()


def test_latlong_to_cube_to_latlong_of_a_smooth_map():
    img = smooth_radiance(latlong.texel_directions(64))
    faces = resample.latlong_to_cube(img, 32)
    np.testing.assert_allclose(faces, smooth_radiance(cubemap.texel_directions(32)), atol=1e-3)
    back = resample.cube_to_latlong(faces, 64)
    np.testing.assert_allclose(back, img, atol=3e-3)


def test_latlong_to_cube_supersampling_averages_sub_texels():
    img = np.random.default_rng(3).random((16, 32, 3))
    assert resample.latlong_supersampling(16, 4) == 3
    faces = resample.latlong_to_cube(img, 4, samples=3)
    fine = resample.latlong_to_cube(img, 12, samples=1)
    np.testing.assert_allclose(faces, fine.reshape(6, 4, 3, 4, 3, 3).mean(axis=(2, 4)), atol=1e-6)


def test_cube_sampling_is_seamless():
    n = 8
    faces = np.random.default_rng(1).random((6, n, n, 3))
    # At texel centres the lookup returns the texels.
    np.testing.assert_allclose(
        resample.sample_cube(faces, cubemap.texel_directions(n)), faces, 1e-6
    )
    # On the edge between +Z (its s = 1 column) and +X (its s = 0 column), halfway between
    # texel rows: the mean of the two texels across the edge.
    t = (3 + 0.5) / n
    on_edge = cubemap.uv_to_direction(4, [1.0, t])
    expected = 0.5 * (faces[4, 3, n - 1] + faces[0, 3, 0])
    np.testing.assert_allclose(resample.sample_cube(faces, on_edge), expected, atol=1e-6)
    # A constant cube stays constant everywhere, corners included.
    ones = np.ones((6, n, n, 3))
    np.testing.assert_allclose(resample.sample_cube(ones, DIRECTIONS[:2000]), 1.0, atol=1e-6)
    # A smooth field is reproduced to the bilinear error inside the faces. Within half a
    # texel of an edge the neighbour face's texel is not where the footprint assumes
    # (GL's seamless filtering is only first-order accurate there), so the error is larger.
    smooth = smooth_radiance(cubemap.texel_directions(32))
    error = np.abs(resample.sample_cube(smooth, DIRECTIONS) - smooth_radiance(DIRECTIONS))
    _, uv = cubemap.direction_to_uv(DIRECTIONS)
    interior = np.minimum(uv, 1.0 - uv).min(axis=-1) > 0.5 / 32
    assert error[interior].max() < 1e-3
    assert error.max() < 5e-3


def test_round_trips_through_paraboloid_and_spheremap():
    faces = smooth_radiance(cubemap.texel_directions(16))
    para = resample.cube_to_paraboloid(faces, 48, 2)
    assert para.shape == (2, 48, 48, 3)
    back = resample.paraboloid_to_cube(para, 16, 2)
    np.testing.assert_allclose(back, faces, atol=5e-3)
    angle = np.pi / 5
    R = np.array([[np.cos(angle), 0, np.sin(angle)], [0, 1, 0], [-np.sin(angle), 0, np.cos(angle)]])
    sphere = resample.cube_to_spheremap(faces, 96, R)
    back = resample.spheremap_to_cube(sphere, 16, R)
    # Away from the rim's stretched neighbourhood of view -Z the round trip is bilinear-accurate.
    view_z = cubemap.texel_directions(16) @ R[:, 2]
    keep = view_z > -0.9
    np.testing.assert_allclose(back[keep], faces[keep], atol=5e-3)
    # The sphere map's centre is the camera's +Z axis, seen through the rotation.
    centre = sphere[47:49, 47:49].mean(axis=(0, 1))
    np.testing.assert_allclose(centre, smooth_radiance(R[:, 2]), atol=2e-3)
