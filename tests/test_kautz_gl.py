"""Method kautz on the GPU (EGL): eq. 12 in the shaders, the glossy lookup, the GPU
projection against its NumPy twin, the cross-face mip chain and the dynamic cube."""

import itertools

import moderngl
import numpy as np
import pytest

from envstudio.core import cubemap, latlong
from envstudio.core.env_sampling import luminance
from envstudio.core.sh_bands import BAND_SETS, a_hat, band_indices, sh_basis
from envstudio.core.sh_lights import DiffuseProjector
from envstudio.core.transforms import normal_matrix, perspective, rotation_xyz, translation
from envstudio.engine.session import RenderSession
from envstudio.envmap.conversions import read_cube
from envstudio.envmap.dynamic_cube import DynamicCube, face_view
from envstudio.envmap.mipmaps import build_cross_face_mipmaps, edge_jumps, mipmapped_cube
from envstudio.gpu.mesh import GpuMesh
from envstudio.gpu.uniforms import set_uniform
from envstudio.methods.kautz.method import STATIC_HEIGHT
from envstudio.prefilter.sh_gpu import GpuDiffuseProjector, block_rows
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Transform
from envstudio.scene.primitives import box
from test_render_gl import render as render_frame
from test_render_gl import sphere_geometry, sphere_scene

SIZE = (96, 96)


def render(session: RenderSession, method: str = "kautz", **params) -> np.ndarray:
    return render_frame(session, method, SIZE, **params)


def sun_and_sky(height: int = 64) -> Environment:
    """A sky gradient and a 5° sun of 200 × the sky's radiance, lat-long."""
    d = latlong.texel_directions(height)
    sky = 0.2 + 0.8 * np.clip(d[..., 1:2], 0.0, 1.0) * np.array([0.4, 0.6, 1.0])
    sun = np.array([0.3, 0.5, 0.81]) / np.linalg.norm([0.3, 0.5, 0.81])
    disc = (d @ sun > np.cos(np.radians(5.0)))[..., None]
    return Environment((sky + disc * np.array([200.0, 160.0, 120.0])).astype(np.float32))


def upload_faces(ctx: moderngl.Context, faces: np.ndarray) -> moderngl.TextureCube:
    cube = mipmapped_cube(ctx, faces.shape[1])
    rgba = np.concatenate([faces, np.ones((*faces.shape[:3], 1))], -1).astype(np.float32)
    for face in range(6):
        cube.write(face, rgba[face].tobytes())
    return cube


def test_constant_environment_gives_pi_l_irradiance_per_vertex_and_per_pixel(gl_ctx):
    L = np.array([0.25, 0.5, 0.75], np.float32)
    env = Environment.constant(L, height=STATIC_HEIGHT)
    session = RenderSession(sphere_scene(env), ctx=gl_ctx, cube_size=64)
    hit, _, _ = sphere_geometry(session.camera)
    for per_pixel in (False, True):
        # k_d / π · πL = L whatever F is, since the glossy term is L too.
        img = render(session, kd=1.0, fresnel=0.0, per_pixel=per_pixel, lod_bias=2.0)
        inside = hit & (img.sum(-1) > 0)
        assert inside.sum() > 0.9 * hit.sum()
        np.testing.assert_allclose(img[inside], np.broadcast_to(L, img[inside].shape), rtol=2e-3)
    session.release()


@pytest.mark.parametrize(("coefficients", "lights"), [(9, 0), (49, 32)])
def test_per_pixel_diffuse_is_the_numpy_model(gl_ctx, coefficients, lights):
    env = sun_and_sky(STATIC_HEIGHT)
    session = RenderSession(sphere_scene(env, rings=96), ctx=gl_ctx, cube_size=64)
    img = render(
        session,
        kd=1.0,
        fresnel=0.0,
        per_pixel=True,
        lod_bias=0.0,
        sh_coefficients=str(coefficients),
        lights=lights,
    )
    hit, normal, view = sphere_geometry(session.camera)
    core = hit & (np.sum(normal * view, -1) > 0.9)  # F = (1 − cos θ)^5 < 1e-5 there
    projector = DiffuseProjector.for_latlong(
        STATIC_HEIGHT, coefficients=coefficients, lights=lights
    )
    expected = projector.project(env.radiance).irradiance(normal[core]) / np.pi
    np.testing.assert_allclose(img[core], expected, rtol=2e-3, atol=1e-4)
    session.release()


def test_per_vertex_interpolation_stays_close_to_per_pixel(gl_ctx):
    session = RenderSession(sphere_scene(sun_and_sky(), rings=96), ctx=gl_ctx, cube_size=64)
    per_vertex = render(session, kd=1.0, fresnel=0.0, per_pixel=False)
    per_pixel = render(session, kd=1.0, fresnel=0.0, per_pixel=True)
    hit, normal, view = sphere_geometry(session.camera)
    core = hit & (np.sum(normal * view, -1) > 0.9)
    difference = np.abs(per_vertex[core] - per_pixel[core]) / per_pixel[core]
    assert difference.mean() < 0.01
    session.release()


def test_glossy_lookup_at_b_0_is_the_mirror(gl_ctx):
    session = RenderSession(sphere_scene(sun_and_sky()), ctx=gl_ctx, cube_size=64)
    mirror = render(session, "mirror", fresnel=1.0, kd=0.0)
    kautz = render(session, lod_bias=0.0, fresnel=1.0, kd=0.0)
    hit, _, _ = sphere_geometry(session.camera)
    assert np.abs(mirror[hit]).max() > 0
    np.testing.assert_allclose(kautz, mirror, rtol=1e-6, atol=1e-7)  # F = 1 up to rounding
    session.release()


def test_raising_b_lowers_the_variance_monotonically(gl_ctx):
    from test_render_gl import six_colour_environment

    session = RenderSession(sphere_scene(six_colour_environment()), ctx=gl_ctx, cube_size=64)
    hit, _, _ = sphere_geometry(session.camera)
    variances = [
        luminance(render(session, lod_bias=b, fresnel=1.0, kd=0.0)[hit]).var()
        for b in (0.0, 0.5, 1.0, 2.0, 3.0, 4.0)
    ]
    assert all(a > b for a, b in itertools.pairwise(variances)), variances
    session.release()


def test_level_mode_blur_does_not_depend_on_the_image_size(gl_ctx):
    from test_render_gl import six_colour_environment

    session = RenderSession(sphere_scene(six_colour_environment()), ctx=gl_ctx, cube_size=64)
    spread = {}
    for mode in ("bias", "level"):
        for size in (48, 96):
            method = session.method("kautz")
            method.values.update({"lod_mode": mode, "lod_bias": 3.0, "fresnel": 1.0, "kd": 0.0})
            session.render_offscreen(method, (size, size))
            hit, _, _ = sphere_geometry(session.camera, (size, size))
            spread[mode, size] = luminance(session.read_hdr()[hit]).std()
    assert spread["level", 48] == pytest.approx(spread["level", 96], rel=0.03)
    assert spread["bias", 48] < 0.95 * spread["bias", 96], "a bias blurs small images more"
    session.release()


def test_sliders_change_uniforms_only(gl_ctx):
    session = RenderSession(sphere_scene(sun_and_sky()), ctx=gl_ctx, cube_size=64)
    first = render(session, lod_bias=0.0)
    compiled = session.programs.compile_count
    for values in ({"lod_bias": 3.0}, {"fresnel": 0.9}, {"kd": 0.1}):
        assert not np.array_equal(render(session, **values), first), values
    assert session.programs.compile_count == compiled
    session.release()


def test_environment_data_is_rebuilt_only_when_the_environment_changes(gl_ctx):
    session = RenderSession(sphere_scene(sun_and_sky()), ctx=gl_ctx, cube_size=64)
    method = session.method("kautz")
    passes = [set(session.render_offscreen(method, SIZE).passes_ms) for _ in range(2)]
    assert "kautz.project" in passes[0] and "kautz.project" not in passes[1]
    session.gpu_scene.set_environment(Environment.constant((1.0, 1.0, 1.0)))
    assert "kautz.project" in session.render_offscreen(method, SIZE).passes_ms
    method.release()
    method.release()  # idempotent
    session.release()


@pytest.mark.parametrize(("coefficients", "lights"), [(9, 0), (25, 8), (49, 32)])
def test_gpu_projection_matches_its_numpy_twin(gl_ctx, programs, coefficients, lights):
    n = 64
    faces = cubemap.texel_directions(n)
    sky = 0.2 + 0.8 * np.clip(faces[..., 1:2], 0.0, 1.0) * np.array([0.4, 0.6, 1.0])
    suns = [(np.array([0.3, 0.5, 0.81]), 300.0), (np.array([-0.7, 0.1, 0.2]), 80.0)]
    for direction, radiance in suns:
        disc = faces @ (direction / np.linalg.norm(direction)) > np.cos(np.radians(6.0))
        sky = sky + disc[..., None] * radiance
    cube = upload_faces(gl_ctx, sky)
    rows = gl_ctx.buffer(reserve=block_rows(coefficients, lights) * 16)
    projector = GpuDiffuseProjector(gl_ctx, programs)
    projector.project(cube, 0, coefficients, lights, 1.0, rows)
    gpu = np.frombuffer(rows.read(), np.float32).reshape(-1, 4)
    cpu = DiffuseProjector.for_cube(n, coefficients=coefficients, lights=lights).project(sky)
    expected = cpu.block(lights)
    count = len(cpu.coefficients)
    np.testing.assert_allclose(gpu[:count], expected[:count], atol=2e-4 * np.abs(expected).max())
    if lights:
        assert len(cpu.lights) >= 3, "both suns cover several tiles"
        light_rows = slice(count, count + lights)  # unused slots are zero on both sides
        np.testing.assert_allclose(gpu[light_rows, :3], expected[light_rows, :3], atol=1e-4)
        np.testing.assert_allclose(gpu[light_rows, 3], expected[light_rows, 3], rtol=0.05)
        rgb_rows = slice(count + lights, count + 2 * lights)
        np.testing.assert_allclose(gpu[rgb_rows], expected[rgb_rows], rtol=1e-3, atol=1e-6)
    for obj in (projector, rows, cube):
        obj.release()


def test_gpu_projection_of_a_combination_of_basis_functions_comes_back(gl_ctx, programs):
    n = 128
    c = np.random.default_rng(3).normal(size=(9, 3))
    cube = upload_faces(gl_ctx, sh_basis(cubemap.texel_directions(n), BAND_SETS[9]) @ c)
    rows = gl_ctx.buffer(reserve=block_rows(9, 0) * 16)
    GpuDiffuseProjector(gl_ctx, programs).project(cube, 0, 9, 0, 1.0, rows)
    degree, _ = band_indices(BAND_SETS[9])
    scale = np.array([a_hat(int(b)) for b in degree])[:, None]
    gpu = np.frombuffer(rows.read(), np.float32).reshape(-1, 4)[:9, :3] / scale
    np.testing.assert_allclose(gpu, c, atol=1e-4)


def edge_spots(n: int = 64) -> np.ndarray:
    """Black cube faces with a 4° spot just inside one face of each of the 12 edges."""
    d = cubemap.texel_directions(n)
    axes = np.concatenate([np.eye(3), -np.eye(3)])[[0, 3, 1, 4, 2, 5]]  # +X −X +Y −Y +Z −Z
    faces = np.zeros((6, n, n, 3))
    for f, g in itertools.combinations(range(6), 2):
        if abs(axes[f] @ axes[g]) > 0.5:
            continue  # opposite faces share no edge
        spot = axes[f] + 0.9 * axes[g] + 0.5 * np.cross(axes[f], axes[g])
        faces[d @ (spot / np.linalg.norm(spot)) > np.cos(np.radians(4.0))] = 1.0
    return faces


def test_cross_face_filter_closes_every_edge_at_a_high_level(gl_ctx, programs):
    faces = edge_spots()
    box_chain = upload_faces(gl_ctx, faces)
    box_chain.build_mipmaps()
    cross_chain = upload_faces(gl_ctx, faces)
    build_cross_face_mipmaps(gl_ctx, programs, cross_chain)
    level = 5  # 2 x 2 texels per face
    for cube, seamless in ((box_chain, False), (cross_chain, True)):
        texels = read_cube(cube, level, programs)
        across, _ = edge_jumps(texels)
        relative = np.array(list(across.values())) / texels.mean()
        assert len(relative) == 12
        if seamless:
            assert relative.max() < 0.6, relative
        else:
            assert relative.min() > 0.8, relative
    box_chain.release()
    cross_chain.release()


def test_dynamic_cube_reflects_a_moved_object_only_on_its_side(gl_ctx):
    scene = sphere_scene(Environment.constant((0.3, 0.3, 0.3)), rings=96)
    red = Node(
        "red box",
        box(0.6),
        transform=Transform(translation=(1.6, 0.0, 0.0)),
        role="local",
        color=(0.9, 0.05, 0.05),
    )
    scene.nodes.append(red)
    session = RenderSession(scene, ctx=gl_ctx, cube_size=64)
    session.renderer.display["background"] = False
    values = {"dynamic": True, "lod_bias": 0.0, "fresnel": 1.0, "kd": 0.0}
    before = render(session, **values)
    red.transform = Transform(translation=(1.6, 0.7, 0.0))
    session.gpu_scene.refresh_transforms()
    after = render(session, **values)
    hit, normal, _ = sphere_geometry(session.camera)
    changed = hit & (np.abs(after - before).max(-1) > 0.02)
    assert changed.sum() > 20, "the reflection of the box moved"
    assert np.all(normal[changed][:, 0] > 0.0), "only the side facing the box (+X) changed"
    far_side = hit & (normal[..., 0] < -0.2)
    np.testing.assert_allclose(after[far_side], before[far_side], atol=1e-5)
    red_side = hit & (normal[..., 0] > 0.5)
    # The box, albedo (0.9, 0.05, 0.05) under 0.3 everywhere, has radiance (0.27, 0.015, 0.015).
    assert (before[red_side][:, 0] - before[red_side][:, 2]).max() > 0.2, "the box shows red"
    session.release()


def test_dynamic_mode_renders_the_room_without_gl_errors(gl_ctx):
    from envstudio.io.scene_file import load_scene

    session = RenderSession(load_scene("room"), ctx=gl_ctx, cube_size=64)
    method = session.method("kautz")
    method.values.update({"dynamic": True, "cross_face_filter": True, "lights": 8})
    stats = session.render_offscreen(method, (64, 48))
    assert gl_ctx.error == "GL_NO_ERROR"
    assert {"kautz.capture", "kautz.mipmaps", "kautz.sh", "kautz"} <= set(stats.passes_ms)
    hdr = session.read_hdr()
    assert np.isfinite(hdr).all() and hdr.max() > 0
    session.release()


def test_figure_commands_write_the_grid_and_the_seam_pair(tmp_path, capsys):
    from envstudio.cli import main
    from envstudio.io.images import read_image

    grid = tmp_path / "grid.png"
    assert main(["figure", "kautz-grid", "--size", "24x20", "-o", str(grid)]) == 0
    assert read_image(grid).shape == (4 * 20 + 6, 4 * 24 + 6, 3)
    seams = tmp_path / "seams.png"
    assert main(["figure", "kautz-seams", "--size", "24x20", "-o", str(seams)]) == 0
    assert read_image(seams).shape == (20, 2 * 24 + 2, 3)
    out = capsys.readouterr().out
    assert "rows b = 0.0, 0.8, 1.7, 2.4" in out and "cross-face across" in out
    assert main(["figure", "kautz-grid", "-o", str(tmp_path / "grid.exr")]) == 2


def six_pass_capture(ctx, programs, environment, sh9, objects, size):
    """Seed 000 section 5.1 as written: six 90° renders from the origin, one per face."""
    background = programs.get("frame/background.glsl")
    local = programs.get("frame/local_diffuse.glsl")
    fbo = ctx.framebuffer(
        [ctx.texture((size, size), 4, dtype="f4")], ctx.depth_renderbuffer((size, size))
    )
    projection = perspective(90.0, 1.0, 0.01, 1000.0)
    environment.use(location=0)
    background["u_environment"] = 0
    faces = []
    for face in range(6):
        view = face_view(face, (0.0, 0.0, 0.0))
        with ctx.scope(fbo, enable_only=moderngl.NOTHING):
            ctx.viewport = (0, 0, size, size)
            fbo.clear(depth=1.0)
            inverse = np.linalg.inv(projection.astype(np.float64) @ view).astype(np.float32)
            set_uniform(background, "u_inverse_view_projection", inverse)
            ctx.vertex_array(background, []).render(moderngl.TRIANGLES, vertices=3)
            ctx.enable(moderngl.DEPTH_TEST)
            for name, value in (("u_sh9", sh9), ("u_view", view), ("u_projection", projection)):
                set_uniform(local, name, value)
            for mesh, model, normal, albedo in objects:
                set_uniform(local, "u_model", model)
                set_uniform(local, "u_normal_matrix", normal)
                set_uniform(local, "u_albedo", albedo)
                mesh.render(local)
            pixels = np.frombuffer(fbo.read(components=4, dtype="f4"), np.float32)
        faces.append(pixels.reshape(size, size, 4)[..., :3])
    return np.stack(faces)


def test_one_pass_strip_capture_equals_six_face_renders(gl_ctx, programs):
    """The instanced strip (one draw per object) renders what six face passes render.

    Two boxes straddle face edges (+X/+Y and -Z/-X/-Y), so the clip distances that
    cut each instance to its sixth of the strip are exercised on every side.
    """
    n = 32
    faces = 0.2 + 0.6 * (cubemap.texel_directions(n) * 0.5 + 0.5)
    environment = upload_faces(gl_ctx, faces)
    sh9 = np.linspace(0.1, 0.9, 27).reshape(9, 3).astype(np.float32)
    mesh = GpuMesh(gl_ctx, box(0.8))
    objects = []
    red, green = ((1.3, 1.1, 0.3), (0.9, 0.1, 0.1)), ((-1.1, -1.0, -1.2), (0.1, 0.8, 0.2))
    for offset, albedo in (red, green):
        model = translation(offset) @ rotation_xyz((20.0, 35.0, 10.0))
        objects.append((mesh, model, normal_matrix(model), albedo))
    expected = six_pass_capture(gl_ctx, programs, environment, sh9, objects, n)
    dynamic = DynamicCube(gl_ctx, programs, n)
    dynamic.capture(environment, sh9, objects, (0.0, 0.0, 0.0))
    captured = read_cube(dynamic.cube)[..., :3]
    assert gl_ctx.error == "GL_NO_ERROR"
    covered = np.abs(expected - faces).max(-1) > 1e-3
    assert all(covered[face].sum() > 20 for face in (0, 1, 2, 3, 5)), covered.sum((1, 2))
    assert covered[4].sum() == 0, "the boxes lie off +Z"
    np.testing.assert_allclose(captured[~covered], faces[~covered], atol=1e-6)
    mismatched = np.abs(captured - expected).max(-1) > 1e-4
    assert mismatched.sum() <= 0.01 * covered.sum(), mismatched.sum((1, 2))
    dynamic.release()
    environment.release()
