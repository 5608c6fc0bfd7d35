"""Method ``rsibr`` on the GPU (seed 002 §3.3, §4): generated maps, the frame, the cache."""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.bake.rsibr import bake as rb
from envstudio.core.rsibr_warp import view_frame
from envstudio.envmap.conversions import read_texture
from envstudio.methods.rsibr.generator import MapGenerator
from envstudio.render.session import RenderSession
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene
from envstudio.scene.primitives import uv_sphere

N = 64


@pytest.mark.parametrize("warp", ["mirror", "normal"])
@pytest.mark.parametrize("per_pixel", [False, True])
def test_generated_map_at_a_sample_view_is_that_sample(gl_ctx, programs, warp, per_pixel):
    views, faces = rb.geodesic_views(12)
    frames = np.stack([view_frame(v) for v in views])
    maps = np.random.default_rng(0).uniform(0, 1, (12, N, N, 3)).astype(np.float32)
    textures = []
    for image in maps:
        tex = gl_ctx.texture((N, N), 3, image.tobytes(), dtype="f4")
        tex.repeat_x = tex.repeat_y = False
        textures.append(tex)
    generator = MapGenerator(gl_ctx, programs, N)
    centre = (np.arange(N) + 0.5) / N - 0.5
    inside = np.hypot(*np.meshgrid(centre, centre)) < 0.5 - 0.5 / N
    for j in (0, 5, 11):
        out = read_texture(
            generator.generate(textures, views, frames, faces, frames[j], warp, per_pixel=per_pixel)
        )
        indices, weights = generator.sources
        assert weights[list(indices).index(j)] == 1.0
        # white noise is the worst case: a 1e-5 texel offset moves the value by ~1e-5
        np.testing.assert_allclose(out[inside], maps[j][inside], atol=2e-5)
    generator.release()
    for tex in textures:
        tex.release()


def _sphere_session(gl_ctx, colour) -> RenderSession:
    camera = OrbitCamera(azimuth=30.0, elevation=20.0, distance=3.0, fov_y=45.0)
    scene = Scene(Environment.constant(colour), [Node("sphere", uv_sphere(1.0, 32, 64))], camera)
    return RenderSession(scene, ctx=gl_ctx)


@pytest.mark.parametrize(
    ("brdf", "params"), [("phong", {"fresnel": 1.0, "kd": 0.0}), ("lambertian", {"kd": 1.0})]
)
def test_sphere_under_a_constant_environment_is_that_constant(gl_ctx, brdf, params):
    colour = np.array([0.25, 0.5, 0.75], np.float32)
    session = _sphere_session(gl_ctx, colour)
    method = session.method("rsibr")
    method.values.update({"brdf": brdf, "map_size": 16, **params})
    session.renderer.display["background"] = False
    session.render_offscreen(method, (48, 48))
    img = session.read_hdr()
    hit = img.sum(-1) > 0
    assert hit.sum() > 200
    np.testing.assert_allclose(img[hit], np.broadcast_to(colour, img[hit].shape), rtol=1e-4)
    session.release()


def test_bakes_are_cached_and_a_refused_file_is_baked_again(gl_ctx):
    session = _sphere_session(gl_ctx, (0.5, 0.5, 0.5))
    first = session.method("rsibr")
    first.values.update({"map_size": 16})
    session.render_offscreen(first, (32, 32))
    files = list(rb.cache_dir().glob("*.rsibr"))
    assert len(files) == 1 and first.last_bake_seconds is not None
    second = type(first)(gl_ctx, session.programs)
    second.values.update(first.values.as_dict())
    session.render_offscreen(second, (32, 32))
    assert second.last_bake_seconds is None  # loaded from the cache
    files[0].write_bytes(b"corrupt")
    third = type(first)(gl_ctx, session.programs)
    third.values.update(first.values.as_dict())
    session.render_offscreen(third, (32, 32))
    assert third.last_bake_seconds is not None
    assert rb.load_bake(files[0], size=16).brdf == "phong"
    for m in (first, second, third):
        m.release()
    session.release()
