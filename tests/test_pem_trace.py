"""Segmented ray tracer of the PEM bake (seed 003 §3–4, Figure 4): pem/bake/trace and views."""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.core.fresnel import schlick
from envstudio.methods.pem.bake import SceneTracer, arc_views, grid_views
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene, Transform
from envstudio.scene.material import Material
from envstudio.scene.primitives import uv_sphere

CONSTANT = (0.7, 0.5, 0.3)


def _sphere(name, translation=(0.0, 0.0, 0.0), kd=(0.0, 0.0, 0.0), fresnel=1.0, role="reflector"):
    return Node(
        name,
        uv_sphere(1.0, 64, 128),
        Material(kd=kd, fresnel=fresnel),
        Transform(translation),
        role,
    )


def _cam(**kw):
    return OrbitCamera(**{"azimuth": 0.0, "elevation": 0.0, "distance": 4.0, "fov_y": 40.0, **kw})


def test_constant_environment_mirror_sphere():
    scene = Scene(Environment.constant(CONSTANT), [_sphere("ball")])
    view = SceneTracer(scene).trace(_cam(), size=48, samples=4)
    on = view.coverage[0] > 0
    assert on.sum() > 300
    np.testing.assert_allclose(
        view.distant[0][on], np.broadcast_to(CONSTANT, (on.sum(), 3)), atol=1e-5
    )
    assert view.local_alpha.max() == 0.0
    # a perfect mirror shows the constant; so does the background
    np.testing.assert_allclose(
        view.composite, np.broadcast_to(CONSTANT, view.composite.shape), atol=1e-5
    )


def test_fresnel_layer_is_schlick_of_the_view_angle():
    scene = Scene(
        Environment.constant(CONSTANT), [_sphere("ball", kd=(0.4, 0.4, 0.4), fresnel=0.2)]
    )
    tracer = SceneTracer(scene)
    view = tracer.trace(_cam(), size=32, samples=1)
    on = view.coverage[0] == 1
    # F lies in [f_λ, 1], is f_λ head-on (the image centre), and the diffuse layer is
    # k_d/π · πL = k_d·L under a constant sky
    assert view.fresnel[0][on].min() >= 0.2 - 1e-6 and view.fresnel[0][on].max() <= 1.0
    np.testing.assert_allclose(
        view.diffuse[0][on], 0.4 * np.array(CONSTANT) * np.ones((on.sum(), 3)), rtol=2e-2
    )
    centre = view.fresnel[0][16, 16]
    assert centre == pytest.approx(float(schlick(0.2, 1.0)), abs=2e-3)


@pytest.mark.parametrize("samples", [1, 4])
def test_layers_recombine_to_the_composite(room_tracer, samples):
    tracer, scene = room_tracer
    view = tracer.trace(scene.camera, size=48, samples=samples)
    rebuilt = view.recombine()
    on = view.coverage.sum(axis=0) > 0
    assert on.sum() > 100 and view.local_alpha.max() > 0  # the teapot sees itself
    if samples == 1:
        # C = (1 − F)·d + F·(α_L·L + (1 − α_L)·D) on reflector pixels, exactly
        p = np.argmax(view.coverage, axis=0)
        i, j = np.nonzero(on)
        F = view.fresnel[p[i, j], i, j][:, None]
        a = view.local_alpha[p[i, j], i, j][:, None]
        expect = (1 - F) * view.diffuse[p[i, j], i, j] + F * (
            a * view.local_rgb[p[i, j], i, j] + (1 - a) * view.distant[p[i, j], i, j]
        )
        np.testing.assert_allclose(view.composite[i, j], expect, rtol=1e-5, atol=1e-5)
        np.testing.assert_allclose(rebuilt, view.composite, rtol=1e-5, atol=1e-5)
    else:
        # exact up to the variation of F, d, D inside a pixel: small on average
        err = np.abs(rebuilt - view.composite)[on].mean()
        assert err < 0.02 * view.composite[on].mean()
        np.testing.assert_allclose(rebuilt[~on], view.composite[~on], atol=1e-5)


def test_rehit_goes_to_the_local_layer():
    # sphere A mirrors sphere B (f_λ 0.5, black): rays off A that hit B are local
    env = Environment.constant((1.0, 1.0, 1.0))
    a = _sphere("A")
    b = _sphere("B", translation=(2.5, 0.0, 0.0), fresnel=0.5)
    view = SceneTracer(Scene(env, [a, b])).trace(_cam(), size=64, samples=1)
    on = view.coverage[0] == 1
    local = view.local_alpha[0] > 0
    assert local.sum() > 20
    # distant passes through B: defined everywhere on A, and the constant
    np.testing.assert_allclose(view.distant[0][on], 1.0, atol=1e-5)
    # what B returns is dimmed by its Schlick F in [0.5, 1): the sky seen in B is darker
    assert view.local_rgb[0][local].max() < 0.999
    assert view.local_rgb[0][local].mean() < 0.8
    np.testing.assert_allclose(view.composite[local], view.local_rgb[0][local], atol=1e-5)
    # analytic check: pixel-centre rays off the unit sphere that hit sphere B
    cam = _cam()
    pix, o, d = SceneTracer(Scene(env, [a])).primary_rays(cam, 64, 1)
    half = np.tan(np.radians(cam.fov_y) / 2)
    col, row = pix % 64 + 0.5, pix // 64 + 0.5
    d = np.stack([(col / 32 - 1) * half, (1 - row / 32) * half, -np.ones_like(col)], 1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    bq = np.einsum("ij,ij->i", o, d)
    disc = bq**2 - (np.einsum("ij,ij->i", o, o) - 1)
    hit = disc > 0
    t = -bq - np.sqrt(np.maximum(disc, 0))
    p = o + t[:, None] * d
    r = d - 2 * np.einsum("ij,ij->i", d, p)[:, None] * p
    q = p - (2.5, 0, 0)
    bq2 = np.einsum("ij,ij->i", q, r)
    disc2 = bq2**2 - (np.einsum("ij,ij->i", q, q) - 1)
    expect = (hit & (disc2 > 0) & (bq2 < 0)).reshape(64, 64)
    inside = on & hit.reshape(64, 64)
    agree = (expect[inside] == local[inside]).mean()
    assert agree > 0.97


def test_arc_views_step():
    base = OrbitCamera(azimuth=25.0, elevation=0.0, distance=3.0)
    space = arc_views(base, count=100, step=1.0)
    assert len(space) == 100 and space.shape == (100,)
    cams = space.cameras()
    np.testing.assert_allclose(np.diff([c.azimuth for c in cams]), 1.0)
    assert cams[0].azimuth == 25.0
    dirs = np.array([c.position - c.target for c in cams])
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    angles = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", dirs[:-1], dirs[1:]), -1, 1)))
    np.testing.assert_allclose(angles, 1.0, atol=1e-4)
    assert {c.distance for c in cams} == {3.0}


def test_grid_views_and_bad_input():
    base = OrbitCamera(azimuth=0.0, elevation=10.0, distance=3.0)
    grid = grid_views(base, 5, 2.0, 3, 5.0)
    assert grid.shape == (3, 5) and len(grid.cameras()) == 15
    assert [c.elevation for c in grid.cameras()[::5]] == [10.0, 15.0, 20.0]
    with pytest.raises(ValueError, match="count"):
        arc_views(base, count=0)
    with pytest.raises(ValueError, match="coincide"):
        arc_views(base, count=5, step=90.0)
    with pytest.raises(ValueError, match="step"):
        arc_views(base, count=3, step=0.0)
    with pytest.raises(ValueError, match="89"):
        grid_views(base, 2, 1.0, 10, 10.0)
    with pytest.raises(ValueError, match="no reflector"):
        SceneTracer(Scene(Environment.constant(CONSTANT), [_sphere("wall", role="local")]))


@pytest.fixture(scope="module")
def room_tracer():
    from envstudio.io.scene_file import load_scene

    scene = load_scene("room")
    return SceneTracer(scene), scene


def test_halved_view_keeps_the_layers_composing(room_tracer):
    """A coarser footprint (models.py): the 2 × 2 means, with α·L and (1 − α)·D exact."""
    tracer, scene = room_tracer
    view = tracer.trace(scene.camera, size=48, samples=2)
    half = view.halved()
    assert half.size == 24 and half.samples == 4 * view.samples

    def box(a):
        return 0.25 * (a[:, 0::2, 0::2] + a[:, 1::2, 0::2] + a[:, 0::2, 1::2] + a[:, 1::2, 1::2])

    a = view.local_alpha[..., None].astype(np.float64)
    assert (half.local_alpha > 0).any() and (half.local_alpha < 1).any()
    np.testing.assert_allclose(half.incident(), box(view.incident()), atol=1e-5)
    np.testing.assert_allclose(half.local_alpha, box(view.local_alpha), atol=1e-6)
    np.testing.assert_allclose(
        half.local_alpha[..., None] * half.local_rgb, box(a * view.local_rgb), atol=1e-5
    )
    np.testing.assert_allclose(half.coverage, box(view.coverage), atol=1e-6)
    np.testing.assert_allclose(half.composite, box(view.composite[None])[0], atol=1e-6)
    assert view.halved().halved().size == 12
