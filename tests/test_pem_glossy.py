"""Glossy PEM bakes (issue 31 part 5; seed 003 §7): the tracer samples the Phong lobe about r.

The lobe is the reference's, (N + 1)/(2π) max(r·l, 0)^N (shaders/common/sampling.glsl):
a huge N is the mirror, and under an environment linear in the direction the
lobe's mean is the mirror's value pulled in by the lobe's mean cosine (N + 1)/(N + 2).
"""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.core.latlong import texel_directions
from envstudio.methods.pem.bake import SceneTracer
from envstudio.methods.pem.bake.bake import _part_header, plan_bake
from envstudio.methods.pem.bake.views import arc_views
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene, Transform
from envstudio.scene.material import Material
from envstudio.scene.primitives import uv_sphere


def test_huge_exponent_is_the_mirror_and_unset_is_todays_bake():
    from envstudio.io.scene_file import load_scene

    scene = load_scene("room")
    tracer = SceneTracer(scene)
    mirror = tracer.trace(scene.camera, size=16, samples=1, seed=3)
    glossy = tracer.trace(scene.camera, size=16, samples=1, seed=3, phong_exponent=1e6)
    assert glossy.phong_exponent == 1e6 and mirror.phong_exponent == 0.0
    # the lobe (half-width ~0.1°) moves each reflection ray by about a milliradian
    assert np.abs(glossy.composite - mirror.composite).max() < 1e-3
    np.testing.assert_array_equal(glossy.coverage, mirror.coverage)
    np.testing.assert_array_equal(glossy.ray_direction, mirror.ray_direction)  # lookups: r
    # 0 (as None): the parameters, hence the key, and the part identity of a bake made
    # before the option; N > 0 changes all three
    args = {"size": 16, "samples": 1, "em_size": 4, "lookups": "cpu", "probe": False}
    zero, n50 = (
        plan_bake("room", lambda c: arc_views(c, 2, 1.0), phong_exponent=n, **args) for n in (0, 50)
    )
    assert "phong_exponent" not in zero.parameters and n50.parameters["phong_exponent"] == 50.0
    assert zero.key != n50.key
    assert zero.tasks[0].phong_exponent == 0.0 and n50.tasks[0].phong_exponent == 50.0
    assert "phong_exponent" not in _part_header(zero.key, zero.tasks[0])["task"]
    assert _part_header(n50.key, n50.tasks[0])["task"]["phong_exponent"] == 50.0


def test_lobe_mean_under_a_linear_environment():
    """L(d) = 1 + d_z/2: a lobe sample's mean is 1 + ½·(N + 1)/(N + 2)·r_z (exact, unclipped)."""
    n_exp = 10.0
    image = 1.0 + 0.5 * texel_directions(256, 512)[..., 2:3] * np.ones(3)
    ball = Node("ball", uv_sphere(1.0, 64, 128), Material(kd=(0.0,) * 3, fresnel=1.0),
                Transform((0.0, 0.0, 0.0)), "reflector")  # fmt: skip
    scene = Scene(Environment(image.astype(np.float32)), [ball])
    camera = OrbitCamera(azimuth=0.0, elevation=0.0, distance=4.0, fov_y=40.0)
    view = SceneTracer(scene).trace(camera, size=32, samples=16, seed=1, phong_exponent=n_exp)
    assert view.local_alpha.max() == 0.0  # a convex ball sees no reflector again
    # pixels all of whose samples have r·n > 0.9: the lobe below the surface is < 1e-4 of it
    r, nrm = view.ray_direction.astype(np.float64), view.ray_normal.astype(np.float64)
    grazing = np.bincount(view.ray_pixel, np.einsum("ij,ij->i", r, nrm) <= 0.9, minlength=32**2)
    keep = (view.coverage[0].ravel() == 1.0) & (grazing == 0)
    assert keep.sum() >= 15
    sel = keep[view.ray_pixel]
    measured = view.distant[0].reshape(-1, 3)[keep].mean()
    mirror = 1.0 + 0.5 * r[sel, 2].mean()  # what a mirror would show
    lobe = 1.0 + 0.5 * (n_exp + 1.0) / (n_exp + 2.0) * r[sel, 2].mean()
    # ~300 samples of std ~0.04: the mean is known to ~0.002; the lobe moves it by ~0.04
    assert measured == pytest.approx(lobe, abs=0.01)
    assert abs(measured - mirror) > 0.025
