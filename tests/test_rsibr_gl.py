"""Method ``rsibr`` on the GPU (seed 002 §3.3, §4): generated maps, the frame, the cache."""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.engine.session import RenderSession
from envstudio.envmap.conversions import read_texture
from envstudio.io.scene_setup import build_scene
from envstudio.methods.rsibr.bake import bake as rb
from envstudio.methods.rsibr.generator import MapGenerator
from envstudio.methods.rsibr.warp import view_frame
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


def test_bakes_are_cached_and_a_refused_file_is_baked_again(gl_ctx, capsys):
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
    methods = [first, second]
    corruptions = (
        lambda p: p.write_bytes(b"corrupt"),
        lambda p: p.write_bytes(b""),
        lambda p: (p.unlink(), p.mkdir()),  # a folder where the entry was
    )
    for corrupt in corruptions:
        corrupt(files[0])
        capsys.readouterr()
        again = type(first)(gl_ctx, session.programs)
        again.values.update(first.values.as_dict())
        session.render_offscreen(again, (32, 32))
        assert again.last_bake_seconds is not None  # discarded with a note, baked again
        notes = [line for line in capsys.readouterr().err.splitlines() if "discarded" in line]
        assert len(notes) == 1 and files[0].name in notes[0]
        assert rb.load_bake(files[0], size=16).brdf == "phong"
        methods.append(again)
    for m in methods:
        m.release()
    session.release()


def test_a_sharp_phong_sphere_looks_like_mirror(gl_ctx):
    """N = 5000 is nearly a mirror: rsibr's frame is `mirror`'s, blurred by its 64² map.

    Catches what the constant environments cannot: the warp's passes leave the depth
    test off, and the reflector's back faces then land over its front faces.
    """
    scene = build_scene("studio", None, None)
    scene.nodes[:] = [Node("sphere", uv_sphere(1.0, 48, 96))]
    session = RenderSession(scene, ctx=gl_ctx)
    images = []
    for name, values in (
        ("mirror", {"fresnel": 1.0, "kd": 0.0}),
        ("rsibr", {"fresnel": 1.0, "kd": 0.0, "phong_exponent": 5000.0}),
    ):
        method = session.method(name)
        method.values.update(values)
        session.render_offscreen(method, (96, 96))
        images.append(session.read_ldr().astype(np.float64) / 255.0)
    session.release()
    difference = np.abs(images[0] - images[1]).max(axis=-1)
    assert difference.mean() < 0.03
    assert (difference > 0.25).mean() < 0.03  # the blur at the lights and the silhouette


def test_figure_rsibr_warp_writes_figure_4_whose_generated_panel_is_the_method_map(
    gl_ctx, tmp_path, capsys
):
    from envstudio.cli import main
    from envstudio.core.images import to_ldr, upright
    from envstudio.io.images import read_image

    output = tmp_path / "figure4.png"
    argv = ["figure", "rsibr-warp", "--param", "map_size=32", "--size", "64x64", "-o", output]
    assert main([str(a) for a in argv]) == 0
    assert "generated map" in capsys.readouterr().out
    image = read_image(output)
    image = np.asarray(image if image.dtype == np.uint8 else np.round(255 * image), np.uint8)
    n = 64  # 32² maps drawn 2 pixels a texel
    assert image.shape[:2] == (2 * n + 2, 4 * n + 6)

    session = RenderSession(build_scene("studio", None, None), ctx=gl_ctx)
    method = session.method("rsibr")
    method.values["map_size"] = 32
    session.render_offscreen(method, (64, 64))
    generated = read_texture(method.generate(method.last_frame_d))[..., :3]
    expected = upright(to_ldr(generated), 2)
    y, x = n + 2, 3 * (n + 2)
    np.testing.assert_array_equal(image[y : y + n, x : x + n, :3], expected)
    # the three warped panels are not the generated one, and the sources differ from them
    assert not np.array_equal(image[y : y + n, :n, :3], expected)
    session.release()


def test_window_bakes_in_the_background_and_the_panel_shows_figure_4(gl_ctx):
    """With a frame budget every bake, the first one included, runs a view or more per
    frame (progress in (0, 1), nothing drawn yet); the panel's Figure 4 section then draws
    the seven thumbnails through the ImGui renderer."""
    from imgui_bundle import imgui

    from envstudio.ui.imgui_renderer import ImGuiRenderer
    from envstudio.ui.panels import _panel_figure

    session = RenderSession(build_scene("studio", None, None), ctx=gl_ctx)
    method = session.method("rsibr")
    method.values["map_size"] = 16
    method.frame_budget_ms = 0.0  # one view per frame (the conftest's cache is empty)
    session.render_offscreen(method, (32, 32))
    assert method.progress() == 1 / 12
    assert "baking phong maps 1/12" in method.status_line()
    assert method.bake is None
    for _ in range(11):
        session.render_offscreen(method, (32, 32))
    assert method.progress() is None and method.bake is not None

    context = imgui.create_context()
    imgui.get_io().set_ini_filename(None)
    renderer = ImGuiRenderer(gl_ctx)
    fbo = gl_ctx.simple_framebuffer((320, 240))
    try:
        io = imgui.get_io()
        io.display_size = (320, 240)
        io.delta_time = 1.0 / 60.0
        imgui.new_frame()
        imgui.set_next_window_pos((0, 0))
        imgui.set_next_window_size((320, 240))
        imgui.begin("Method")
        imgui.set_next_item_open(True)
        _panel_figure(method, renderer, session.renderer.display)
        imgui.end()
        imgui.render()
        fbo.use()
        fbo.clear(0.0, 0.0, 0.0, 1.0)
        renderer.render(imgui.get_draw_data())
        assert len(method._thumbnails) == 7
        drawn = {
            cmd.get_tex_id() for lst in imgui.get_draw_data().cmd_lists for cmd in lst.cmd_buffer
        }
        assert {tex.glo for tex in method._thumbnails} <= drawn
        pixels = np.frombuffer(fbo.read(components=3), np.uint8)
        assert pixels.reshape(240, 320, 3).std() > 10.0
    finally:
        renderer.release()
        fbo.release()
        imgui.destroy_context(context)
        session.release()
