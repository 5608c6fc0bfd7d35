"""Method ``parallax`` (Lagarde and Zanuttini 2012) on the GPU (EGL), its proxy volume, and
the scene files that declare one: at infinity it is ``mirror``; in the box room it reflects
the walls where they stand, seen from each point of the ball, not from the probe. Its Phong
chain: constant in a constant environment, and a level against a brute-force convolution."""

import numpy as np
import pytest

from envstudio.core import cubemap
from envstudio.core.fresnel import schlick
from envstudio.engine.session import RenderSession
from envstudio.envmap.conversions import read_cube
from envstudio.envmap.mipmaps import mipmapped_cube, write_cube_level
from envstudio.io.scene_file import load_scene
from envstudio.prefilter.chain_gpu import gpu_phong_cube_chain, texel_exponents
from envstudio.scene.environment import Environment
from envstudio.scene.proxy import BoxProxy, SphereProxy
from test_bad_input import assert_one_line_error, run_cli
from test_render_gl import render, sphere_geometry, sphere_scene
from test_static_environment_gl import RADIUS, footprint, room_with_mirror_ball, wall_radiance

SIZE = (64, 64)
MIRROR = {"fresnel": 1.0, "kd": 0.0}
SHARP = {**MIRROR, "phong_exponent": 1.0e6}  # the chain's level is below 0 on a 64² cube
FAR = 1.0e6
#: The declared probe: off the ball's centre, so that the cube is captured elsewhere.
PROBE_OFFSET = np.array([0.9, 0.7, -0.6])


def test_proxy_exit_distances():
    """The Python twin of shaders/parallax/proxy.glsl on rays whose exits are known."""
    box = BoxProxy((-1.0, -2.0, -3.0), (1.0, 2.0, 3.0))
    origins = np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.0, 0.0, 0.0]])
    directions = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.6, 0.8]])
    np.testing.assert_allclose(box.exit_distance(origins, directions), [1.0, 1.5, 2.0 / 0.6])
    assert box.contains((0.9, 1.9, -2.9)) and not box.contains((0.0, 2.5, 0.0))
    sphere = SphereProxy((1.0, 0.0, 0.0), 2.0)
    np.testing.assert_allclose(sphere.exit_distance(origins, directions), [3.0, 1.5, np.sqrt(3)])
    assert sphere.contains((2.9, 0.0, 0.0)) and not sphere.contains((-1.5, 0.0, 0.0))


@pytest.fixture
def ball_session(gl_ctx):
    """The room with a mirror ball of radius 0.4 at the teapot's centre (static-EM test's)."""
    scene, centre = room_with_mirror_ball()
    assert isinstance(scene.proxy, BoxProxy), "room.toml declares the room's box as its proxy"
    session = RenderSession(scene, ctx=gl_ctx, cube_size=64)
    yield session, centre
    session.release()


@pytest.mark.parametrize(
    "proxy", [BoxProxy((-FAR, -FAR, -FAR), (FAR, FAR, FAR)), SphereProxy((0.0, 0.0, 0.0), FAR)]
)
def test_proxy_at_infinity_is_mirror(ball_session, proxy):
    """A proxy a million units away: every ray's hit lies along r from the probe, so the
    lookup is mirror's, pixel for pixel over the whole image (the ball and the room)."""
    session, _ = ball_session
    session.scene.proxy = proxy
    session.renderer.display["background"] = True
    mirror = session.method("mirror")
    mirror.values.update(MIRROR)
    session.render_offscreen(mirror, SIZE)
    expected = session.read_hdr()
    parallax = session.method("parallax")
    parallax.values.update(SHARP)
    session.render_offscreen(parallax, SIZE)
    image = session.read_hdr()
    np.testing.assert_allclose(image, expected, rtol=1e-4, atol=1e-6)
    assert parallax.status_line().startswith(f"proxy {proxy.shape}")


def object_clearance(scene, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """(...,) angle in radians from rays (origins, directions (..., 3)) to the nearest
    coloured object's circumscribed cone (< 0: the ray may see the object)."""
    clearance = np.full(directions.shape[:-1], np.inf)
    for node in scene.local_objects():
        if node.name == "room":
            continue
        lo, hi = node.mesh.bounds().astype(np.float64) * node.transform.scale
        middle = node.transform.matrix()[:3, 3] + (lo + hi) / 2 - origins
        distance = np.linalg.norm(middle, axis=-1)
        cosine = np.sum(directions * middle, -1) / distance
        outer = np.arcsin(np.minimum(np.linalg.norm(hi - lo) / 2 / distance, 1.0))
        clearance = np.minimum(clearance, np.arccos(np.clip(cosine, -1.0, 1.0)) - outer)
    return clearance


def test_ball_off_the_probe_reflects_the_walls_where_they_stand(ball_session):
    """The probe declared 1.3 units from the ball's centre (its own capture there). Centre
    pixel: the wall behind the camera. Every pixel whose ray from the ball's surface point
    meets a wall away from its edges and from the objects, and whose proxy hit the probe
    sees away from them too: that wall's shade. The probe's cube read along r misses it."""
    session, centre = ball_session
    scene = session.scene
    probe = centre + PROBE_OFFSET
    scene.proxy = BoxProxy(scene.proxy.minimum, scene.proxy.maximum, tuple(probe))
    parallax = session.method("parallax")
    parallax.values.update(SHARP)
    session.renderer.display["background"] = False
    assert "parallax.capture" in session.render_offscreen(parallax, SIZE).passes_ms
    img = session.read_hdr()
    sh9 = session.gpu_scene.sh9.astype(np.float64)
    hit, normal, view = sphere_geometry(session.camera, SIZE, centre, RADIUS)
    reflected = 2 * np.sum(normal * view, -1, keepdims=True) * normal - view
    points = centre + RADIUS * normal

    behind = session.camera.position - points[SIZE[1] // 2, SIZE[0] // 2]
    behind_camera, _ = wall_radiance(scene, sh9, centre, behind / np.linalg.norm(behind))
    np.testing.assert_allclose(img[SIZE[1] // 2, SIZE[0] // 2], behind_camera, rtol=1e-3)

    walls, margin = wall_radiance(scene, sh9, points, reflected)
    exits = scene.proxy.exit_distance(points, reflected)
    lookup = points + exits[..., None] * reflected - probe
    lookup /= np.linalg.norm(lookup, axis=-1, keepdims=True)
    _, probe_margin = wall_radiance(scene, sh9, probe, lookup)
    texel = 1.5 * np.pi / 2 / 64  # rasterised edges of the 64² capture fall within a texel
    blur = 3.0 * np.maximum(footprint(reflected), footprint(lookup))
    facing = np.sum(normal * view, -1) > 0.3
    clear = (object_clearance(scene, points, reflected) > blur) & (
        object_clearance(scene, probe, lookup) > blur + texel
    )
    on_wall = hit & facing & clear & (margin > blur) & (probe_margin > blur + texel)
    assert on_wall.sum() > 0.2 * hit.sum(), (on_wall.sum(), hit.sum())
    assert len({tuple(np.round(c, 3)) for c in walls[on_wall]}) >= 4
    np.testing.assert_allclose(img[on_wall], walls[on_wall], rtol=1e-3)

    # Where the walls are seen clearly from the ball: the probe's cube read along r, as
    # without the correction, shows the wrong shade far more often.
    seen = hit & facing & (object_clearance(scene, points, reflected) > blur) & (margin > blur)
    uncorrected = render(session, "parallax", SIZE, parallax=False, **SHARP)
    wrong = [np.abs(i[seen] / walls[seen] - 1).max(-1) > 0.01 for i in (img, uncorrected)]
    counts = (seen.sum(), wrong[0].sum(), wrong[1].sum())  # measured: 1179, 0, 106
    assert counts[1] <= 0.01 * counts[0] and counts[2] >= 0.05 * counts[0], counts


ROOM_LIKE = """name = "{name}"
[environment]
file = "hdr/studio.exr"
{proxy}
[[object]]
primitive = "sphere"
[[object]]
primitive = "room"
size = 4.0
role = "local"
"""


@pytest.mark.parametrize(
    ("proxy", "method", "fragments"),
    [
        (
            "",
            "parallax",
            ["scene bare has local objects but no proxy", '[proxy] shape = "box"', "radius"],
        ),
        (
            '[proxy]\nshape = "box"\nmin = [1.0, -2.0, -2.0]\nmax = [2.0, 2.0, 2.0]',
            "mirror",
            ["bare.toml", "box [1, -2, -2]..[2, 2, 2] does not contain", "[0, 0, 0]"],
        ),
        (
            '[proxy]\nshape = "sphere"\ncentre = [0.0, 0.0, 0.0]\nradius = 3.0\n'
            "probe = [0.0, 0.0, 3.5]",
            "parallax",
            ["bare.toml", "sphere [0, 0, 0] radius 3 does not contain proxy.probe"],
        ),
        ('[proxy]\nshape = "sphere"\nradius = 3.0', "mirror", ["proxy.centre is missing"]),
        ('[proxy]\nshape = "cone"', "mirror", ["proxy.shape = 'cone'", "box, sphere"]),
    ],
)
def test_bad_proxy_is_one_line(capsys, tmp_path, proxy, method, fragments):
    scene = tmp_path / "bare.toml"
    scene.write_text(ROOM_LIKE.format(name="bare", proxy=proxy))
    out = tmp_path / "o.png"
    argv = ["render", "--scene", str(scene), "--method", method, "--size", "16x16", "-o", str(out)]
    status, err = run_cli(capsys, *argv)
    assert_one_line_error(status, err, *fragments)
    assert not out.exists()


def test_shipped_room_declares_its_walls_and_studio_needs_no_proxy(gl_ctx):
    """room: its box is the proxy, probed from the teapot's centre. studio has nothing but
    the environment at infinity: no proxy needed, the lookup is along r (mirror's)."""
    room = load_scene("room")
    walls = next(n for n in room.local_objects() if n.name == "room")
    lo, hi = walls.mesh.bounds() * walls.transform.scale + walls.transform.translation
    assert room.proxy == BoxProxy(tuple(lo), tuple(hi))
    studio = load_scene("studio")
    assert studio.proxy is None
    session = RenderSession(studio, ctx=gl_ctx, cube_size=64)
    try:
        parallax = render(session, "parallax", (32, 32), **SHARP)
        mirror = render(session, "mirror", (32, 32), **MIRROR)
        np.testing.assert_allclose(parallax, mirror, rtol=1e-4, atol=1e-6)
        assert "no proxy in scene studio" in session.method("parallax").status_line()
    finally:
        session.release()


def test_constant_environment_every_chain_level_and_the_image_are_the_constant(gl_ctx):
    """A box proxy around the sphere (the distance correction spreads N' over the chain's
    levels): every level of the Phong chain is the constant, the image is eq. 8's
    ((1 − F) k_d + F) times it, and a second frame does not rebuild the chain."""
    colour = np.array([0.25, 0.5, 1.0], np.float32)
    scene = sphere_scene(Environment.constant(colour))
    scene.proxy = BoxProxy((-2.0, -2.5, -3.0), (4.0, 3.0, 2.0))
    session = RenderSession(scene, ctx=gl_ctx, cube_size=64)
    values = {"fresnel": 0.3, "kd": 0.2, "phong_exponent": 20.0}
    values.update(sh_coefficients="9", lights=0)
    parallax = session.method("parallax")
    parallax.values.update(values)
    session.renderer.display["background"] = False
    assert "parallax.prefilter" in session.render_offscreen(parallax, SIZE).passes_ms
    assert "parallax.prefilter" not in session.render_offscreen(parallax, SIZE).passes_ms
    img = session.read_hdr()
    chain = parallax._chain
    assert chain.size == (64, 64)
    for level in range(7):
        faces = read_cube(chain, level)[..., :3]
        np.testing.assert_allclose(faces, np.broadcast_to(colour, faces.shape), rtol=1e-5)
    hit, normal, view = sphere_geometry(session.camera, SIZE)
    n_dot_v = np.sum(normal * view, -1)
    core = hit & (n_dot_v > 0.2)  # away from the silhouette's partly covered pixels
    fresnel = schlick(0.3, n_dot_v[core])[:, None]
    np.testing.assert_allclose(img[core], ((1 - fresnel) * 0.2 + fresnel) * colour, rtol=5e-3)
    session.release()


def test_chain_level_matches_a_brute_force_phong_convolution_of_the_cube(gl_ctx, programs):
    """Level 2 of the Phong chain of a 32² cube (N_2 = 16, 8² faces) against the sum over
    every source texel of (N + 1)/2π max(⟨r, l⟩, 0)^N L Δω (exact solid angles), over the
    sum of the kernel's weights, relative to the level's mean: mean error under 0.3 %, worst
    texel under 2 % (measured: 0.06 % and 0.98 %; a smooth gradient and a lamp 40 times
    brighter, 2 × 2 texels)."""
    n, level = 32, 2
    directions = cubemap.texel_directions(n)
    radiance = np.stack(
        [1.0 + 0.5 * directions[..., 0], 1.0 + 0.5 * directions[..., 1], 1.5 - directions[..., 2]],
        -1,
    )
    radiance[4, 10:12, 20:22] = 40.0  # on −Y
    source = mipmapped_cube(gl_ctx, n)
    write_cube_level(source, 0, radiance)
    source.build_mipmaps()
    chain = gpu_phong_cube_chain(gl_ctx, programs, source, n)
    exponent = texel_exponents(n)[level]
    assert exponent == 16.0
    got = read_cube(chain, level, programs)[..., :3].reshape(-1, 3)
    targets = cubemap.texel_directions(n >> level).reshape(-1, 3)
    cosines = np.maximum(targets @ directions.reshape(-1, 3).T, 0.0)
    weights = (exponent + 1) / (2 * np.pi) * cosines**exponent
    weights *= cubemap.texel_solid_angles(n).reshape(-1)
    expected = weights @ radiance.reshape(-1, 3) / weights.sum(1, keepdims=True)
    error = np.abs(got - expected) / expected.mean()
    assert error.mean() < 0.003 and error.max() < 0.02, (error.mean(), error.max())
    for tex in (chain, source):
        tex.release()
