"""Seed 002's math without GL: icosahedron, spherical barycentrics (§3.4), warps (§3.3)."""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.core import icosahedron as ico
from envstudio.core import spheremap
from envstudio.methods.rsibr import warp as w


def _unit(rng: np.random.Generator, n: int) -> np.ndarray:
    d = rng.normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def _disc_points(rng: np.random.Generator, n: int, radius: float = 0.49) -> np.ndarray:
    """(n, 2) sphere-map points strictly inside the disc."""
    angle = rng.uniform(0, 2 * np.pi, n)
    rho = radius * np.sqrt(rng.uniform(0, 1, n))
    return 0.5 + rho[:, None] * np.stack([np.cos(angle), np.sin(angle)], axis=-1)


def test_icosahedron_is_regular_and_closed():
    v, f = ico.icosahedron()
    assert v.shape == (12, 3) and f.shape == (20, 3)
    np.testing.assert_allclose(np.linalg.norm(v, axis=-1), 1.0)
    assert np.all(np.linalg.det(v[f]) > 0)  # counter-clockwise from outside
    edges = {tuple(sorted(e)) for t in f for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    assert len(edges) == 30  # Euler: 12 - 30 + 20 = 2
    assert np.isclose(ico.spherical_excess(*np.moveaxis(v[f], 1, 0)).sum(), 4 * np.pi)
    assert np.all(np.abs(v[:, 1]) < 0.99)  # no vertex on ±Y: +Y is a valid up everywhere
    v42, f42 = ico.subdivide(v, f)
    assert v42.shape == (42, 3) and f42.shape == (80, 3)
    assert np.isclose(ico.spherical_excess(*np.moveaxis(v42[f42], 1, 0)).sum(), 4 * np.pi)


def test_every_direction_finds_exactly_one_containing_face():
    v, f = ico.icosahedron()
    d = _unit(np.random.default_rng(1), 20000)
    face = ico.find_face(d, v, f)
    a, b, c = np.moveaxis(v[f[face]], 1, 0)
    for x, y in ((a, b), (b, c), (c, a)):
        assert np.all(np.einsum("ni,ni->n", d, np.cross(x, y)) >= -1e-12)


def test_ties_on_edges_and_vertices_take_the_lowest_face():
    v, f = ico.icosahedron()
    for i, j in ((0, 1), (3, 7), (5, 11)):
        shared = [k for k, t in enumerate(f) if {i, j} <= set(t)]
        if len(shared) != 2:
            continue
        for t in (0.25, 0.5, 0.8):
            d = (1 - t) * v[i] + t * v[j]
            assert ico.find_face(d, v, f) == min(shared)
    for i in range(12):
        around = [k for k, t in enumerate(f) if i in t]
        assert len(around) == 5 and ico.find_face(v[i], v, f) == min(around)


def test_index_wrapping_operator():
    assert [ico.wrap_index(a, 3) for a in (-1, 0, 1, 2, 3)] == [2, 0, 1, 2, 0]


def test_weights_nonnegative_sum_to_one_and_match_the_dihedral_form():
    v, f = ico.icosahedron()
    d = _unit(np.random.default_rng(2), 500)
    for x in d:
        _face, idx, weights = ico.view_weights(x, v, f)
        assert np.all(weights >= 0) and np.isclose(weights.sum(), 1.0)
        areas = [ico.spherical_excess_dihedral(x, v[idx], i) for i in range(3)]
        np.testing.assert_allclose(weights, np.array(areas) / sum(areas), atol=1e-7)


def test_weights_at_vertices_and_face_centres():
    v, f = ico.icosahedron()
    for t in f:
        for k in range(3):
            expected = np.eye(3)[k]
            np.testing.assert_allclose(ico.spherical_barycentric(v[t[k]], v[t]), expected)
    centres = ico.face_centres(v, f)
    np.testing.assert_allclose(ico.spherical_barycentric(centres, v[f]), 1 / 3, atol=1e-12)


def test_weights_are_continuous_across_a_shared_edge():
    v, f = ico.icosahedron()
    i, j = f[0][0], f[0][1]
    other = next(k for k, t in enumerate(f) if k != 0 and {i, j} <= set(t))
    mid = v[i] + v[j]
    mid /= np.linalg.norm(mid)
    for eps in (1e-3, 1e-5):
        weights = {}
        for face in (0, other):
            centre = ico.face_centres(v, f[[face]])[0]
            d = mid + eps * (centre - mid)
            d /= np.linalg.norm(d)
            assert ico.find_face(d, v, f) == face
            weights[face] = dict(
                zip(f[face], ico.spherical_barycentric(d, v[f[face]]), strict=False)
            )
        for vertex in (i, j):
            assert abs(weights[0][vertex] - weights[other][vertex]) < 10 * eps
        opposite = next(x for x in f[0] if x not in (i, j))
        assert weights[0][opposite] < 10 * eps


@pytest.mark.parametrize("warp", w.WARPS)
def test_g_and_its_inverse_round_trip(warp):
    rng = np.random.default_rng(3)
    uv = _disc_points(rng, 5000)
    np.testing.assert_allclose(w.g_inverse(w.g_warp(uv, warp), warp), uv, atol=1e-12)
    d = _unit(rng, 5000)
    if warp == "normal":
        d[:, 2] = np.abs(d[:, 2])  # normals of the visible hemisphere
    np.testing.assert_allclose(w.g_warp(w.g_inverse(d, warp), warp), d, atol=1e-9)


def test_g_mirror_is_the_design_sphere_map_and_the_reflection_of_the_normal():
    uv = _disc_points(np.random.default_rng(4), 2000)
    np.testing.assert_allclose(w.g_mirror(uv), spheremap.uv_to_direction(uv), atol=1e-12)
    r = w.g_mirror(uv)
    np.testing.assert_allclose(w.g_mirror_inverse(r), spheremap.direction_to_uv(r), atol=1e-12)
    n, e = w.g_normal(uv), np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(r, 2 * (n @ e)[:, None] * n - e, atol=1e-12)
    # the texel of a mirror direction is the texel of its normal (the chains' last stage)
    np.testing.assert_allclose(w.g_mirror_inverse(r), w.g_normal_inverse(n), atol=1e-12)
    assert np.allclose(w.g_mirror_inverse([0.0, 0.0, -1.0]), [0.5, 0.0])


def test_view_frames_are_right_handed_and_look_from_the_view():
    v, _ = ico.icosahedron()
    for view in [*v, (0, 1, 0), (0, -1, 0), (0, 0, 1)]:
        t = w.view_frame(view)
        np.testing.assert_allclose(t.T @ t, np.eye(3), atol=1e-12)
        assert np.isclose(np.linalg.det(t), 1.0)
        np.testing.assert_allclose(t[:, 2], np.asarray(view) / np.linalg.norm(view))
    t = w.view_frame((0, 0, 1))
    np.testing.assert_allclose(t, np.eye(3))  # the default camera: x right, y up


@pytest.mark.parametrize("warp", w.WARPS)
def test_warp_into_its_own_frame_is_the_identity(warp):
    uv = _disc_points(np.random.default_rng(5), 3000)
    for view in ico.icosahedron()[0][:4]:
        t = w.view_frame(view)
        np.testing.assert_allclose(w.warp_uv(uv, t, t, warp), uv, atol=1e-12)


@pytest.mark.parametrize("warp", w.WARPS)
def test_rotating_the_destination_about_the_view_axis_rotates_the_map(warp):
    uv = _disc_points(np.random.default_rng(6), 3000)
    t_s = w.view_frame((0.3, 0.5, 0.8))
    angle = np.radians(37.0)
    c, s = np.cos(angle), np.sin(angle)
    t_d = t_s @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])  # camera rolled by +37°
    rotated = 0.5 + (uv - 0.5) @ np.array([[c, -s], [s, c]])  # the map turns by −37°
    np.testing.assert_allclose(w.warp_uv(uv, t_s, t_d, warp), rotated, atol=1e-12)


@pytest.mark.parametrize("warp", w.WARPS)
def test_forward_and_inverse_warps_compose_to_the_identity(warp):
    rng = np.random.default_rng(7)
    t_s, t_d = w.view_frame((0.2, 0.9, 0.3)), w.view_frame((0.8, 0.1, 0.6))
    uv_d = _disc_points(rng, 3000, radius=0.3)
    if warp == "normal":  # only normals the source map holds (n · v_s > 0) come back
        uv_d = uv_d[(w.g_normal(uv_d) @ (t_d.T @ t_s))[:, 2] > 1e-6]
    uv_s = w.source_uv(uv_d, t_s, t_d, warp)
    np.testing.assert_allclose(w.warp_uv(uv_s, t_s, t_d, warp), uv_d, atol=1e-9)
    # the direction is preserved in world space
    world_s = w.g_warp(uv_s, warp) @ t_s.T
    world_d = w.g_warp(uv_d, warp) @ t_d.T
    np.testing.assert_allclose(world_s, world_d, atol=1e-9)


def test_singularity_lands_where_the_negated_source_view_warps():
    t_s, t_d = w.view_frame((0.0, 0.3, 1.0)), w.view_frame((0.6, 0.2, 0.7))
    p = w.singularity_uv(t_s, t_d)
    direction = w.g_mirror(p) @ t_d.T  # world direction of that destination point
    np.testing.assert_allclose(direction, -t_s[:, 2], atol=1e-12)
    # approaching it, the inverse warp runs to the source's rim (the pinched, unreliable zone)
    for eps in (1e-2, 1e-4):
        near = p + eps * (0.5 - p) / np.linalg.norm(0.5 - p)
        rho = np.linalg.norm(w.source_uv(near, t_s, t_d, "mirror") - 0.5)
        assert rho > 0.5 - 2 * eps
