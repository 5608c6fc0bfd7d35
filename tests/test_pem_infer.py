"""EM inference of the PEM bake (seed 003 §4, "EM Inference", "Layered EMs"): pem/bake/infer."""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.methods.pem.bake import SceneTracer
from envstudio.methods.pem.bake.infer import (
    BoxGeometry,
    distant_box,
    em_origin,
    infer_distant,
    infer_em,
    local_ellipsoid,
    part_triangles,
    psnr,
    rendering_matrix,
)
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene, Transform
from envstudio.scene.material import Material
from envstudio.scene.primitives import uv_sphere

CONSTANT = (0.7, 0.5, 0.3)


@pytest.fixture(scope="module")
def room():
    from envstudio.io.scene_file import load_scene

    scene = load_scene("room")
    tracer = SceneTracer(scene)
    view = tracer.trace(scene.camera, size=32, samples=4)
    return scene, tracer, view


def test_min_volume_ellipsoid_bounds_the_part(room):
    _, tracer, _ = room
    for part in range(len(tracer.part_names)):
        ell, origin = local_ellipsoid(tracer, part)
        verts = part_triangles(tracer, part).reshape(-1, 3)
        assert ell.contains(verts).all()
        np.testing.assert_allclose(ell.centre, origin)
        lo, hi = verts.min(axis=0), verts.max(axis=0)
        circumscribed = 4 / 3 * np.pi * np.prod(np.sqrt(3) * (hi - lo) / 2)
        assert ell.volume() < circumscribed
        sphere = 4 / 3 * np.pi * np.linalg.norm(verts - origin, axis=1).max() ** 3
        assert ell.volume() < sphere  # the bound: smaller than the bounding sphere


def test_em_origin_is_area_weighted():
    big = [[0, 0, 0], [2, 0, 0], [0, 2, 0]]
    small = [[10, 0, 0], [10.1, 0, 0], [10, 0.1, 0]]
    o = em_origin([big, small])
    a, b = 2.0, 0.005
    expect = (a * np.mean(big, axis=0) + b * np.mean(small, axis=0)) / (a + b)
    np.testing.assert_allclose(o, expect)


def test_rows_sum_to_one_where_rays_meet_the_geometry(room):
    scene, tracer, view = room
    box = distant_box(scene)
    assert isinstance(box, BoxGeometry)
    for part in range(len(tracer.part_names)):
        origin = em_origin(part_triangles(tracer, part))
        for geometry in (box, local_ellipsoid(tracer, part)[0]):
            A, met = rendering_matrix(view, part, geometry, origin, 8)
            assert met.sum() > 20
            sums = np.asarray(A.sum(axis=1)).ravel()
            np.testing.assert_allclose(sums[met], 1.0, atol=1e-9)
            assert (sums[view.coverage[part].ravel() == 0] == 0).all()


def test_a_synthetic_em_comes_back(room):
    scene, tracer, view = room
    part, n = 0, 6
    box = distant_box(scene)
    origin = em_origin(part_triangles(tracer, part))
    A, _ = rendering_matrix(view, part, box, origin, n)
    rng = np.random.default_rng(3)
    x_true = rng.random((6 * n * n, 3))
    b = (A @ x_true).reshape(view.size, view.size, 3)
    res = infer_em(view, part, b, box, origin, n, smoothness=1e-6, matrix=(A, None))
    assert res.psnr > 40
    assert np.isfinite(res.em).all()
    assert psnr(res.render(), (A @ x_true)[res.pixels]) == pytest.approx(res.psnr)


def test_constant_environment_mirror_sphere_infers_the_constant():
    ball = Node("ball", uv_sphere(1.0, 32, 64), Material(kd=(0, 0, 0), fresnel=1.0), Transform())
    scene = Scene(Environment.constant(CONSTANT), [ball])
    tracer = SceneTracer(scene)
    cam = OrbitCamera(azimuth=0.0, elevation=0.0, distance=4.0, fov_y=40.0)
    view = tracer.trace(cam, size=32, samples=1)
    res = infer_distant(scene, tracer, view, 0, size=8)
    assert res.seen.sum() > 50
    np.testing.assert_allclose(
        res.em[res.seen], np.broadcast_to(CONSTANT, (res.seen.sum(), 3)), atol=1e-4
    )
    assert res.psnr > 60
