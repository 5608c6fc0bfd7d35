"""The static environment of seed 003 (Figure 1c) on the GPU (EGL): in a scene with local
objects every environment-map method reflects the scene it sits in, captured once per
scene change from the reflectors' centre; without local objects nothing changes."""

import numpy as np
import pytest

from envstudio.core import cubemap
from envstudio.core.sh import irradiance_sh9
from envstudio.core.sh_lights import DiffuseProjector
from envstudio.core.transforms import normal_matrix, rotation_xyz, translation
from envstudio.engine.session import RenderSession
from envstudio.envmap.conversions import read_cube
from envstudio.envmap.dynamic_cube import DynamicCube
from envstudio.gpu.mesh import GpuMesh
from envstudio.io.scene_file import load_scene
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.graph import Node, Scene, Transform
from envstudio.scene.primitives import box, uv_sphere
from envstudio.shading import sh_irradiance
from test_render_gl import render, six_colour_environment, sphere_geometry, sphere_scene

SIZE = (64, 64)
RADIUS = 0.4  # of the mirror ball put where the room's teapot stands
MIRROR = {"fresnel": 1.0, "kd": 0.0}


def room_with_mirror_ball() -> tuple[Scene, np.ndarray]:
    """The shipped room with its teapot replaced by a ball at the teapot's centre.

    The camera looks at the ball from the room camera's direction, closer. Returns
    the scene and the ball's centre, (3,) float (the capture point of the static
    environment).
    """
    scene = load_scene("room")
    centre = scene.reflector_centre()
    ball = Node("mirror ball", uv_sphere(RADIUS, 64, 128), transform=Transform(tuple(centre)))
    scene.nodes = [ball, *scene.local_objects()]
    scene.camera = OrbitCamera(azimuth=25.0, elevation=18.0, distance=1.1, target=centre)
    return scene, centre


def wall_radiance(scene: Scene, sh9: np.ndarray, centre: np.ndarray, directions: np.ndarray):
    """What the room's walls show along ``directions`` (..., 3) seen from ``centre``.

    The wall of the (inward) room box that a ray from the centre leaves through,
    shaded as the frame shades local objects: albedo / π times the SH9 irradiance
    of the environment along the wall's inward normal (shaders/common/local_diffuse_fs).

    Returns
    -------
    radiance : (..., 3) float64
    margin : (...,) float64
        Angle in radians between the ray and the nearest edge of the wall it hits:
        the ray's angle to the plane through the centre and that edge.
    """
    room = next(n for n in scene.local_objects() if n.name == "room")
    lo, hi = room.mesh.bounds() * room.transform.scale + room.transform.translation  # no rotation
    bound = np.where(directions > 0, hi, lo) - centre  # (..., 3) the planes a ray heads for
    with np.errstate(divide="ignore", invalid="ignore"):
        exits = np.where(directions != 0, bound / directions, np.inf)
    axis = np.argmin(exits, -1)
    normal = -np.sign(np.take_along_axis(directions, axis[..., None], -1)) * np.eye(3)[axis]
    shading = np.asarray(room.color) / np.pi * np.maximum(irradiance_sh9(sh9, normal), 0.0)
    b_a = np.take_along_axis(bound, axis[..., None], -1)
    d_a = np.take_along_axis(directions, axis[..., None], -1)
    sine = np.abs(bound * d_a - b_a * directions) / np.hypot(bound, b_a)
    sine[np.arange(3) == axis[..., None]] = np.inf
    return shading, np.arcsin(np.minimum(sine.min(-1), 1.0))


def footprint(directions: np.ndarray) -> np.ndarray:
    """(h, w) angle in radians that ``directions`` (h, w, 3) turn by from pixel to pixel."""
    dy, dx = np.gradient(directions, axis=(0, 1))
    return np.maximum(np.linalg.norm(dx, axis=-1), np.linalg.norm(dy, axis=-1))


def object_cones(scene: Scene, centre: np.ndarray, directions: np.ndarray):
    """How far rays from the centre pass outside or inside the coloured local objects.

    Each object's bounding box in model space gives two spheres: the circumscribed
    one (a ray outside its cone misses the object) and the inscribed one (a ray
    inside its cone sees the object, nothing standing in front in this room).

    Returns
    -------
    clearance : (...,) float64
        Angle in radians from the ray to the nearest circumscribed cone (< 0: inside).
    depth : dict of str to (...,) float64
        Per object name, the angle by which the ray lies inside the inscribed cone.
    """
    clearance = np.full(directions.shape[:-1], np.inf)
    depth = {}
    for node in scene.local_objects():
        if node.name == "room":
            continue
        lo, hi = node.mesh.bounds().astype(np.float64) * node.transform.scale
        middle = node.transform.matrix()[:3, 3] + (lo + hi) / 2 - centre
        distance = np.linalg.norm(middle)
        angle = np.arccos(np.clip(directions @ middle / distance, -1.0, 1.0))
        outer = np.arcsin(np.linalg.norm(hi - lo) / 2 / distance)
        inner = np.arcsin(np.min(hi - lo) / 2 / distance)
        clearance = np.minimum(clearance, angle - outer)
        depth[node.name] = inner - angle
    return clearance, depth


@pytest.fixture
def room_session(gl_ctx):
    scene, centre = room_with_mirror_ball()
    session = RenderSession(scene, ctx=gl_ctx, cube_size=64)
    session.renderer.display["background"] = False
    yield session, centre
    session.release()


def test_mirror_ball_in_the_room_reflects_the_room(room_session):
    """Centre pixel: the wall behind the camera. Every pixel off the rim whose reflected
    ray meets a wall away from its edges and from the objects: that wall's shade."""
    session, centre = room_session
    img = render(session, "mirror", SIZE, **MIRROR)
    assert session.gpu_scene.static_environment().captured
    scene, sh9 = session.scene, session.gpu_scene.sh9.astype(np.float64)
    hit, normal, view = sphere_geometry(session.camera, SIZE, centre, RADIUS)
    reflected = 2 * np.sum(normal * view, -1, keepdims=True) * normal - view

    behind = session.camera.position - centre
    behind_camera, _ = wall_radiance(scene, sh9, centre, behind / np.linalg.norm(behind))
    row, col = SIZE[1] // 2, SIZE[0] // 2  # pixel centres at 32.5: 1/64 of the ball off axis
    np.testing.assert_allclose(img[row, col], behind_camera, rtol=1e-3)
    raw = session.gpu_scene.cube  # what the mirror reflected before: the photographed interior
    plus_z = read_cube(raw)[4, raw.size[1] // 2, raw.size[0] // 2]  # the view's back, roughly
    assert not np.allclose(behind_camera, plus_z, rtol=0.2)

    walls, margin = wall_radiance(scene, sh9, centre, reflected)
    clearance, _ = object_cones(scene, centre, reflected)
    # Trilinear filtering at the hardware LOD blurs over about two pixel footprints.
    blur = 3.0 * footprint(reflected)
    facing = np.sum(normal * view, -1) > 0.3  # off the rim, where the footprint explodes
    on_wall = hit & facing & (clearance > blur) & (margin > blur)
    assert on_wall.sum() > 0.4 * hit.sum(), (on_wall.sum(), hit.sum())
    # Six walls, six shades 30 % apart or more: a flipped or rotated face cannot pass.
    assert len({tuple(np.round(c, 3)) for c in walls[on_wall]}) >= 4
    np.testing.assert_allclose(img[on_wall], walls[on_wall], rtol=1e-3)


def test_static_cube_holds_the_walls_and_the_objects_where_they_stand(room_session):
    """Texel by texel (level 0, exact texel directions): the walls' shades, and each
    coloured object, with its own colour dominant, in the directions it lies in."""
    session, centre = room_session
    render(session, "mirror", SIZE, **MIRROR)
    static = session.gpu_scene.static_environment()
    faces = read_cube(static.cube).astype(np.float64)
    directions = cubemap.texel_directions(faces.shape[1])
    scene, sh9 = session.scene, session.gpu_scene.sh9.astype(np.float64)
    walls, margin = wall_radiance(scene, sh9, centre, directions)
    clearance, depth = object_cones(scene, centre, directions)
    texel = 1.5 * np.pi / 2 / faces.shape[1]  # rasterised edges fall within a texel or so
    on_wall = (clearance > texel) & (margin > texel)
    np.testing.assert_allclose(faces[on_wall], walls[on_wall], rtol=1e-3)
    for name, inside in depth.items():
        seen = inside > texel
        assert seen.sum() >= 10, f"the static cube should show the {name}"
        albedo = next(n.color for n in scene.local_objects() if n.name == name)
        assert np.all(np.argmax(faces[seen], -1) == np.argmax(albedo)), name


def test_kautz_glossy_and_diffuse_come_from_the_captured_cube(room_session):
    """b = 0, F = 1 is the mirror; the SH diffuse is the projection of the captured cube."""
    session, centre = room_session
    mirror = render(session, "mirror", SIZE, **MIRROR)
    glossy = render(session, "kautz", SIZE, lod_bias=0.0, **MIRROR)
    hit, normal, view = sphere_geometry(session.camera, SIZE, centre, RADIUS)
    np.testing.assert_allclose(glossy[hit], mirror[hit], rtol=1e-6, atol=1e-7)

    diffuse = render(session, "kautz", SIZE, kd=1.0, fresnel=0.0, per_pixel=True)
    static = session.gpu_scene.static_environment()
    faces = read_cube(static.cube, 0, session.programs)  # 64²: the level projected
    core = hit & (np.sum(normal * view, -1) > 0.9)  # F = (1 − cos θ)^5 < 1e-5 there
    expected = DiffuseProjector.for_cube(64).project(faces).irradiance(normal[core]) / np.pi
    np.testing.assert_allclose(diffuse[core], expected, rtol=2e-3, atol=1e-4)
    from_raw = irradiance_sh9(session.gpu_scene.sh9, normal[core]) / np.pi
    assert np.abs(expected / from_raw - 1).max() > 0.2, "the room darkens and tints the SH"


def test_capture_happens_once_per_scene_change(room_session):
    session, _ = room_session
    method = session.method("mirror")
    passes = [set(session.render_offscreen(method, SIZE).passes_ms) for _ in range(2)]
    assert "environment.capture" in passes[0] and "environment.capture" not in passes[1]
    first = session.gpu_scene.static_environment().revision
    red = next(n for n in session.scene.local_objects() if n.name == "red box")
    red.transform = Transform((-1.8, 0.6, -0.8), red.transform.rotation, red.transform.scale)
    session.gpu_scene.refresh_transforms()
    assert "environment.capture" in session.render_offscreen(method, SIZE).passes_ms
    assert session.gpu_scene.static_environment().revision == first + 1
    session.gpu_scene.refresh_transforms()  # a revision without a change: nothing to capture
    assert "environment.capture" not in session.render_offscreen(method, SIZE).passes_ms
    ball = session.scene.reflectors()[0]
    ball.transform = Transform((0.0, 0.3, 0.0))  # the centre moved: capture from there
    session.gpu_scene.refresh_transforms()
    assert "environment.capture" in session.render_offscreen(method, SIZE).passes_ms


@pytest.mark.parametrize("method", ["mirror", "kautz"])
def test_without_local_objects_the_environment_cube_is_used_as_is(gl_ctx, method):
    """Same texture, no capture pass, kautz's SH from the lat-long map (bit-identical)."""
    session = RenderSession(sphere_scene(six_colour_environment()), ctx=gl_ctx, cube_size=64)
    stats = session.render_offscreen(session.method(method), SIZE)
    static = session.gpu_scene.static_environment()
    assert static.cube is session.gpu_scene.cube and not static.captured
    assert "environment.capture" not in stats.passes_ms
    session.release()


def test_kautz_projects_a_read_back_cube_without_compute_shaders(room_session, monkeypatch):
    """On OpenGL 3.3 the captured cube is projected on the CPU: the same image."""
    session, _ = room_session
    values = {"kd": 1.0, "fresnel": 0.0, "per_pixel": True, "lights": 0}
    on_gpu = render(session, "kautz", SIZE, **values)
    monkeypatch.setattr(sh_irradiance, "has_compute", lambda ctx: False)
    # Another threshold (unused without lights) makes kautz project again, now on the CPU.
    on_cpu = render(session, "kautz", SIZE, light_threshold=2.0, **values)
    np.testing.assert_allclose(on_cpu, on_gpu, rtol=1e-3, atol=1e-5)


def test_buffer_copy_of_the_strip_equals_the_compute_copy(gl_ctx, programs):
    """The OpenGL 3.3 path of the capture writes the same faces, texel for texel."""
    n = 32
    environment = DynamicCube(gl_ctx, programs, n)  # any cube with a varied level 0
    colours = np.random.default_rng(3).random((6, n, n, 3))
    faces = np.concatenate([colours, np.ones((6, n, n, 1))], -1)
    for face in range(6):
        environment.cube.write(face, faces[face].astype(np.float32).tobytes())
    mesh = GpuMesh(gl_ctx, box(0.8))
    model = translation((1.2, 0.9, -0.4)) @ rotation_xyz((20.0, 35.0, 10.0))
    objects = [(mesh, model, normal_matrix(model), (0.9, 0.2, 0.1))]
    sh9 = np.linspace(0.1, 0.9, 27).reshape(9, 3)
    captured = []
    for compute_copy in (True, False):
        cube = DynamicCube(gl_ctx, programs, n, compute_copy=compute_copy)
        cube.capture(environment.cube, sh9, objects, (0.0, 0.0, 0.0))
        captured.append(read_cube(cube.cube))
        cube.release()
    assert gl_ctx.error == "GL_NO_ERROR"
    np.testing.assert_array_equal(captured[0], captured[1])
    mesh.release()
    environment.release()
