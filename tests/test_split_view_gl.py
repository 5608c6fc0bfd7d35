"""Split screen and heat map composition (headless)."""

import numpy as np

from envstudio.core.colormap import magma
from envstudio.engine.session import RenderSession
from envstudio.engine.split_view import SplitSettings, SplitView
from envstudio.scene.environment import Environment
from test_render_gl import sphere_scene

SIZE = (64, 48)


def compose(session, view, a, b, settings):
    target = session._ldr_target(SIZE)
    view.render(session.gpu_scene, a, b, session.camera, SIZE, target, settings)
    return session.read_ldr().astype(int)


def test_split_shows_a_left_and_b_right(gl_ctx):
    session = RenderSession(sphere_scene(Environment.constant((0.3, 0.6, 0.9))), ctx=gl_ctx)
    a = session.method("mirror")
    b = type(a)(session.ctx, session.programs)  # a second mirror with other parameters
    a.values["fresnel"] = 0.04
    session.render_offscreen(a, SIZE)
    only_a = session.read_ldr().astype(int)
    session.render_offscreen(b, SIZE)
    only_b = session.read_ldr().astype(int)
    view = SplitView(session.renderer)
    both = compose(session, view, a, b, SplitSettings(split=True, divider=0.5))
    half = SIZE[0] // 2
    assert np.abs(both[:, : half - 2] - only_a[:, : half - 2]).max() <= 1
    assert np.abs(both[:, half + 2 :] - only_b[:, half + 2 :]).max() <= 1
    assert (both[:, half - 1 : half + 1] == 255).all(), "the divider line is white"
    view.release()
    session.release()


def test_heat_map_is_zero_for_identical_methods_and_bright_where_they_differ(gl_ctx):
    session = RenderSession(sphere_scene(Environment.constant((0.5, 0.5, 0.5))), ctx=gl_ctx)
    mirror = session.method("mirror")
    view = SplitView(session.renderer)
    settings = SplitSettings(split=False, heat=True, heat_scale=0.5)
    same = compose(session, view, mirror, mirror, settings)
    zero = np.round(magma(0.0) * 255)
    assert np.abs(same - zero).max() <= 1, "identical renders show no error anywhere"

    other = session.method("reference")
    other.values.update({"fresnel": 1.0, "kd": 0.0, "trace": False})
    mirror.values.update({"fresnel": 0.0, "kd": 0.0})  # F = (1 - n.v)^5: dark in the middle
    heat = compose(session, view, mirror, other, settings)
    centre = heat[SIZE[1] // 2, SIZE[0] // 2]
    corner = heat[0, 0]
    np.testing.assert_allclose(centre, np.round(magma(1.0) * 255), atol=2)
    np.testing.assert_allclose(corner, zero, atol=1)
    view.release()
    session.release()


def test_split_in_a_viewport_puts_the_divider_inside_it(gl_ctx):
    """The window's 3D view is the dock space's central node: a viewport right of the panels;
    the divider stays at its share of that viewport."""
    session = RenderSession(sphere_scene(Environment.constant((0.3, 0.6, 0.9))), ctx=gl_ctx)
    mirror = session.method("mirror")
    view = SplitView(session.renderer)
    offset = 20
    target = gl_ctx.simple_framebuffer((SIZE[0] + offset, SIZE[1]))
    target.clear(0.0, 0.0, 0.0, 1.0)
    settings = SplitSettings(split=True, divider=0.25)
    view.render(
        session.gpu_scene,
        mirror,
        mirror,
        session.camera,
        SIZE,
        target,
        settings,
        (offset, 0, *SIZE),
    )
    pixels = np.frombuffer(target.read(components=3), np.uint8).reshape(SIZE[1], -1, 3)
    white = np.flatnonzero((pixels == 255).all(axis=(0, 2)))
    assert white.tolist() == [offset + SIZE[0] // 4 - 1, offset + SIZE[0] // 4]
    assert (pixels[:, :offset] == 0).all(), "nothing drawn left of the viewport"
    target.release()
    view.release()
    session.release()
