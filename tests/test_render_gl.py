"""Headless GL (EGL): the frame path and the mirror method against analytic answers."""

import numpy as np
import pytest

from envstudio.core.fresnel import schlick
from envstudio.core.latlong import texel_directions
from envstudio.engine.session import RenderSession
from envstudio.io.scene_file import load_scene, shipped_scenes
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene
from envstudio.scene.primitives import uv_sphere

SIZE = (96, 96)

FACE_COLOURS = {  # OpenGL face order +X, -X, +Y, -Y, +Z, -Z
    "+X": (1.0, 0.0, 0.0),
    "-X": (0.0, 1.0, 1.0),
    "+Y": (0.0, 1.0, 0.0),
    "-Y": (1.0, 0.0, 1.0),
    "+Z": (0.0, 0.0, 1.0),
    "-Z": (1.0, 1.0, 0.0),
}


def six_colour_environment(height: int = 64) -> Environment:
    d = texel_directions(height)
    axis = np.argmax(np.abs(d), axis=-1)
    positive = np.take_along_axis(d, axis[..., None], -1)[..., 0] > 0
    names = np.array([["-X", "+X"], ["-Y", "+Y"], ["-Z", "+Z"]])[axis, positive.astype(int)]
    img = np.array([[FACE_COLOURS[n] for n in row] for row in names], dtype=np.float32)
    return Environment(img)


def sphere_scene(
    environment: Environment, distance: float = 3.0, fov: float = 45.0, rings: int = 64
) -> Scene:
    camera = OrbitCamera(azimuth=0.0, elevation=0.0, distance=distance, fov_y=fov)
    return Scene(environment, [Node("sphere", uv_sphere(1.0, rings, 2 * rings))], camera, "sphere")


def render(
    session: RenderSession, method: str = "mirror", size: tuple[int, int] = SIZE, **params
) -> np.ndarray:
    """``method`` with ``params`` over no background: the (h, w, 3) linear frame."""
    m = session.method(method)
    m.values.update(params)
    session.renderer.display["background"] = False
    session.render_offscreen(m, size)
    return session.read_hdr()


def sphere_geometry(camera: OrbitCamera, size=SIZE, centre=(0.0, 0.0, 0.0), radius=1.0):
    """Per-pixel hit mask, normal and view direction of a sphere, by default the unit
    sphere at the origin (NumPy); the normal is the hit point's offset over ``radius``."""
    w, h = size
    inv = np.linalg.inv(
        camera.projection_matrix(w / h).astype(np.float64) @ camera.view_matrix().astype(np.float64)
    )
    x = (np.arange(w) + 0.5) / w * 2 - 1
    y = 1 - (np.arange(h) + 0.5) / h * 2  # row 0 at the top
    X, Y = np.meshgrid(x, y)
    near = np.stack([X, Y, -np.ones_like(X), np.ones_like(X)], -1) @ inv.T
    far = np.stack([X, Y, np.ones_like(X), np.ones_like(X)], -1) @ inv.T
    origin = near[..., :3] / near[..., 3:]
    direction = far[..., :3] / far[..., 3:] - origin
    direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
    origin = (origin - np.asarray(centre, dtype=np.float64)) / radius
    b = np.sum(origin * direction, -1)
    c = np.sum(origin * origin, -1) - 1.0
    disc = b * b - c
    hit = disc > 0
    t = -b - np.sqrt(np.where(hit, disc, 0.0))
    normal = origin + t[..., None] * direction
    return hit, normal, -direction


def test_mirror_sphere_under_constant_environment_is_that_constant(gl_ctx):
    colour = np.array([0.25, 0.5, 0.75], np.float32)
    session = RenderSession(sphere_scene(Environment.constant(colour)), ctx=gl_ctx)
    img = render(session, fresnel=1.0, kd=0.0)
    hit, _, _ = sphere_geometry(session.camera)
    inside = hit & (np.abs(img).sum(-1) > 0)
    assert inside.sum() > 0.9 * hit.sum()
    np.testing.assert_allclose(img[inside], np.broadcast_to(colour, img[inside].shape), atol=1e-3)
    session.release()


def test_mirror_fresnel_matches_schlick_per_pixel(gl_ctx):
    colour = np.array([1.0, 0.5, 0.25], np.float32)
    session = RenderSession(sphere_scene(Environment.constant(colour)), ctx=gl_ctx)
    img = render(session, fresnel=0.04, kd=0.0)
    hit, normal, view = sphere_geometry(session.camera)
    cos_theta = np.sum(normal * view, -1)
    expected = schlick(0.04, cos_theta)[..., None] * colour
    core = hit & (cos_theta > 0.3)  # away from the silhouette, where pixels straddle the edge
    np.testing.assert_allclose(img[core], expected[core], atol=4e-3)
    assert img[core].mean() < 0.2 * colour.mean(), "Fresnel darkens the sphere face-on"
    session.release()


def test_six_colour_cube_centre_shows_face_behind_camera_and_rim_the_sides(gl_ctx):
    session = RenderSession(sphere_scene(six_colour_environment(), 40.0, 3.2), ctx=gl_ctx)
    img = render(session, fresnel=1.0, kd=0.0)
    hit, _, _ = sphere_geometry(session.camera)
    rows, cols = np.nonzero(hit)
    cy, cx = (rows.min() + rows.max()) / 2, (cols.min() + cols.max()) / 2
    radius = (cols.max() - cols.min() + 1) / 2

    def at(dx: float, dy: float) -> np.ndarray:  # offsets in sphere radii, +dy up
        return img[round(cy - dy * radius), round(cx + dx * radius)]

    r45 = np.sin(np.radians(45.0))
    checks = {
        (0.0, 0.0): "+Z",
        (-r45, 0.0): "-X",
        (r45, 0.0): "+X",
        (0.0, r45): "+Y",
        (0.0, -r45): "-Y",
        (0.985, 0.0): "-Z",
    }
    for (dx, dy), face in checks.items():
        np.testing.assert_allclose(
            at(dx, dy),
            FACE_COLOURS[face],
            atol=0.02,
            err_msg=f"offset ({dx:.2f}, {dy:.2f}) should show {face}",
        )
    session.release()


def test_uniform_change_does_not_recompile(gl_ctx):
    session = RenderSession(sphere_scene(Environment.constant((1.0, 1.0, 1.0))), ctx=gl_ctx)
    first = render(session, fresnel=1.0)
    compiled = session.programs.compile_count
    second = render(session, fresnel=0.1)
    assert session.programs.compile_count == compiled
    assert not np.allclose(first, second), "the parameter had no effect"
    session.release()


def test_background_and_exposure_reach_the_display(gl_ctx):
    session = RenderSession(sphere_scene(Environment.constant((0.18, 0.18, 0.18))), ctx=gl_ctx)
    method = session.method("mirror")
    shown = []
    for exposure in (0.0, 1.0):
        session.renderer.display.update({"exposure": exposure, "tonemap": "none"})
        session.render_offscreen(method, SIZE)
        shown.append(session.read_ldr().astype(float))
    corner = (slice(0, 4), slice(0, 4))
    srgb = lambda c: 1.055 * c ** (1 / 2.4) - 0.055  # noqa: E731
    assert shown[0][corner].mean() == pytest.approx(255 * srgb(0.18), abs=1.5)
    assert shown[1][corner].mean() == pytest.approx(255 * srgb(0.36), abs=1.5)
    session.release()


@pytest.mark.parametrize("scene_name", sorted(shipped_scenes()))
def test_every_method_renders_every_shipped_scene(gl_ctx, scene_name):
    session = RenderSession(load_scene(scene_name), ctx=gl_ctx, cube_size=64)
    for name in session.method_names():
        stats = session.render_offscreen(name, (64, 48))
        assert gl_ctx.error == "GL_NO_ERROR", f"{name} on {scene_name}: {gl_ctx.error}"
        hdr = session.read_hdr()
        assert np.isfinite(hdr).all() and hdr.max() > 0, f"{name} on {scene_name} drew nothing"
        assert stats.passes_ms, f"{name} reported no passes"
    session.release()
