"""Method ``pem`` (issue 19): playback equals the bake's rendering matrix, texgen, bad input.

The bake infers maps x through A, the trilinear lookups the playback shader makes
(methods/pem/bake/lookups.py); a playback that drew anything else would not reproduce
A·x. Here random multi-level maps are played back at a sampled view and
compared with A·x over every reflector pixel, A built from the lookups the
playback shader writes (methods/pem/lookups_gl.py).
"""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from envstudio.engine.session import RenderSession
from envstudio.errors import InputFileError
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.io.scene_file import load_scene
from envstudio.methods.pem.atlas import flat_maps
from envstudio.methods.pem.bake.hull import mesh_check
from envstudio.methods.pem.bake.infer import (
    BoxGeometry,
    EllipsoidGeometry,
    distant_box,
    local_ellipsoid,
)
from envstudio.methods.pem.bake.lookups import CHANNELS, MODELS
from envstudio.methods.pem.bake.mip import mip_sizes
from envstudio.methods.pem.bake.trace import SceneTracer
from envstudio.methods.pem.lookups_gl import GlLookups
from envstudio.methods.pem.method import shipped_bake
from envstudio.methods.pem.resident import SLOTS, ResidentViews

R, N = 48, 8
LOD_BIAS = -1.0  # a bake's level bias (methods/pem/bake/lookups.py): the playback adds it too


@pytest.fixture(scope="module")
def room():
    scene = load_scene("room")
    tracer = SceneTracer(scene)
    ellipsoids = [local_ellipsoid(tracer, p) for p in range(len(tracer.part_names))]
    return scene, distant_box(scene), ellipsoids


def _fake_bake(scene, box, ellipsoids, views=2, seed=0, hull_share=0.0):
    """A bake of random maps (every level) on a 2-view arc about the scene camera."""
    rng = np.random.default_rng(seed)
    parts = [n.name for n in scene.reflectors()]
    sizes = mip_sizes(N)
    maps = {}
    for model in MODELS:
        levels = []
        for nk in sizes:
            a = rng.uniform(0.1, 1.0, (views, len(parts), 6, nk, nk, CHANNELS[model]))
            if model == "local":
                a[..., 3] = rng.uniform(0.0, 1.0, a.shape[:-1])
                a[..., :3] *= a[..., 3:]  # premultiplied
            levels.append(a.astype(np.float32))
        maps[model] = levels
    cam = scene.camera
    return SimpleNamespace(
        scene=scene.name,
        parts=parts,
        view_space={
            "kind": "arc",
            "azimuths": [cam.azimuth + 2.0 * k for k in range(views)],
            "elevations": [cam.elevation],
            "distance": cam.distance,
            "target": [float(t) for t in cam.target],
            "fov_y": cam.fov_y,
        },
        maps=maps,
        hull=[rng.random(n.mesh.triangle_count) < hull_share for n in scene.reflectors()],
        mesh_checks=[mesh_check(n) for n in scene.reflectors()],
        box=np.array([box.lo, box.hi]),
        origins=np.array([o for _, o in ellipsoids]),
        ellipsoids=np.array([[e.centre, e.radii] for e, _ in ellipsoids]),
        em_size=N,
        views=views,
        parameters={"lod_bias": LOD_BIAS},
        header={},
    )


def _play(gl_ctx, scene, bake, **values):
    session = RenderSession(scene, ctx=gl_ctx, cube_size=32)
    method = session.method("pem")
    method.show(bake, session.gpu_scene, Path("fake.pem"))
    method.values.update({"snap": True, "kd": 0.0, "fresnel_layer": False, **values})
    session.renderer.display["background"] = False
    session.render_offscreen(method, (R, R))
    return session, method, session.read_hdr().astype(np.float64)


def _expected(
    gl_ctx, scene, bake, camera, view_weights, hull=False, model="layered", texgen="fragment"
):
    """A·x per pixel from the playback shader's own lookups (the bake's matrix)."""
    lookups = GlLookups(scene, ctx=gl_ctx, texgen=texgen).render(
        camera, R, N, bake.box, bake.origins, bake.ellipsoids
    )
    flat = {m: flat_maps(bake.maps[m]).reshape(bake.views, len(bake.parts), -1, 4) for m in MODELS}
    out = np.zeros((R * R, 3))
    for p in range(len(bake.parts)):
        on = lookups.part.ravel() == p
        for v, w in view_weights:
            if model == "sphere":
                a = lookups.matrix("sphere", p, lod_bias=LOD_BIAS)
                incident = a @ flat["sphere"][v, p, :, :3]
            else:
                distant = (
                    lookups.matrix("distant", p, lod_bias=LOD_BIAS) @ flat["distant"][v, p, :, :3]
                )
                local = lookups.matrix("local", p, lod_bias=LOD_BIAS) @ flat["local"][v, p]
                if hull:
                    tri = lookups.triangle.ravel()
                    flags = np.zeros(R * R, bool)
                    flags[on] = bake.hull[p][tri[on]]
                    local[flags] = 0.0
                incident = local[:, :3] + (1.0 - local[:, 3:]) * distant
            out[on] += w * incident[on]
    return out.reshape(R, R, 3), lookups.part >= 0


def _relative_error(got, want, mask):
    return np.abs(got[mask] - want[mask]).max() / np.abs(want[mask]).max()


def test_playback_at_a_sampled_view_equals_the_rendering_matrix(gl_ctx, room):
    scene, box, ellipsoids = room
    bake = _fake_bake(scene, box, ellipsoids)
    session, method, hdr = _play(gl_ctx, scene, bake, path=0.0, blend=False)
    want, mask = _expected(gl_ctx, scene, bake, session.camera, [(0, 1.0)])
    assert mask.sum() > 250  # the teapot and its lid in view
    assert _relative_error(hdr, want, mask) < 1e-3
    # the sphere-at-infinity model through its own matrix
    method.values["em_model"] = "sphere"
    session.render_offscreen(method, (R, R))
    want, _ = _expected(gl_ctx, scene, bake, session.camera, [(0, 1.0)], model="sphere")
    assert _relative_error(session.read_hdr().astype(np.float64), want, mask) < 1e-3
    # the paper's per-vertex texgen, against lookups rendered the same way
    method.values.update({"em_model": "layered", "texgen": "vertex"})
    session.render_offscreen(method, (R, R))
    vertex = session.read_hdr().astype(np.float64)
    want, _ = _expected(gl_ctx, scene, bake, session.camera, [(0, 1.0)], texgen="vertex")
    assert _relative_error(vertex, want, mask) < 1e-3
    assert _relative_error(vertex, hdr, mask) > 0.01  # and it is not the per-fragment image
    session.release()


def test_blended_playback_between_views_and_the_hull_split(gl_ctx, room):
    scene, box, ellipsoids = room
    bake = _fake_bake(scene, box, ellipsoids, seed=1, hull_share=0.5)
    session, method, hdr = _play(gl_ctx, scene, bake, path=0.25, blend=True, hull=True)
    assert method.last_blend.views == (0, 1)
    assert np.allclose(method.last_blend.weights, (0.75, 0.25))
    want, mask = _expected(gl_ctx, scene, bake, session.camera, [(0, 0.75), (1, 0.25)], hull=True)
    assert _relative_error(hdr, want, mask) < 1e-3
    # without the split, hull pixels would show the local layer: the images differ there
    unsplit, _ = _expected(gl_ctx, scene, bake, session.camera, [(0, 0.75), (1, 0.25)])
    assert _relative_error(hdr, unsplit, mask) > 0.05
    session.release()


def test_a_bake_of_more_views_than_the_slots_streams_them_and_plays_the_same(gl_ctx, room):
    """A file of 20 views (the paper's 100 at 256² are 4.2 GB of maps) is not uploaded whole:
    the views a frame blends move into 16 resident slots, and the playback is still A·x of
    those views, also after a sweep over all 20 has evicted and moved them in again."""
    scene, box, ellipsoids = room
    bake = _fake_bake(scene, box, ellipsoids, views=SLOTS + 4, seed=3)
    session, method, _ = _play(gl_ctx, scene, bake, path=0.0, blend=True)
    textures = method._loaded.textures
    assert isinstance(textures, ResidentViews) and textures.slot_count == SLOTS
    for position in np.linspace(0.0, 1.0, 2 * bake.views):  # every view, in and out
        method.values["path"] = position
        session.render_offscreen(method, (R, R))
    assert len(textures.resident) == SLOTS and 0 not in textures.resident  # evicted
    at = 2.5 / (bake.views - 1)  # between views 2 and 3: moved in again
    method.values["path"] = at
    session.render_offscreen(method, (R, R))
    hdr = session.read_hdr().astype(np.float64)
    assert method.last_blend.views == (2, 3) and np.allclose(method.last_blend.weights, 0.5)
    want, mask = _expected(gl_ctx, scene, bake, session.camera, [(2, 0.5), (3, 0.5)])
    assert mask.sum() > 250 and _relative_error(hdr, want, mask) < 1e-3
    assert f"16 of {bake.views} views" in method.status_line()
    session.release()


def test_a_grid_bake_plays_its_sample_and_blends_its_cell_bilinearly(gl_ctx, room):
    """Issue 31: a 2 x 2 grid (elevation-major views): at a corner sample the playback is that
    view's A x; at the cell's centre the four views' A x with weight 1/4 each."""
    scene, box, ellipsoids = room
    bake = _fake_bake(scene, box, ellipsoids, views=4, seed=2)
    cam = scene.camera
    bake.view_space.update(
        kind="grid",
        azimuths=[cam.azimuth, cam.azimuth + 2.0],
        elevations=[cam.elevation, cam.elevation + 2.0],
    )
    session, method, hdr = _play(gl_ctx, scene, bake, path=1.0, path_elevation=1.0)
    assert dict(zip(method.last_blend.views, method.last_blend.weights, strict=True))[3] > 1 - 1e-9
    want, mask = _expected(gl_ctx, scene, bake, session.camera, [(3, 1.0)])
    assert mask.sum() > 250 and _relative_error(hdr, want, mask) < 1e-3
    method.values.update({"path": 0.5, "path_elevation": 0.5})
    session.render_offscreen(method, (R, R))
    assert sorted(method.last_blend.views) == [0, 1, 2, 3]
    assert np.allclose(method.last_blend.weights, 0.25)
    want, mask = _expected(gl_ctx, scene, bake, session.camera, [(v, 0.25) for v in range(4)])
    assert _relative_error(session.read_hdr().astype(np.float64), want, mask) < 1e-3
    session.release()


def test_texgen_matches_the_numpy_geometry(gl_ctx, programs):
    rng = np.random.default_rng(5)
    box = BoxGeometry(lo=np.array([-4.0, -0.5, -4.0]), hi=np.array([4.0, 7.5, 4.0]))
    ellipsoid = EllipsoidGeometry(
        centre=np.array([0.1, 0.3, -0.2]), radii=np.array([0.9, 0.5, 0.7])
    )
    k = 64 * 64
    d = rng.normal(size=(k, 3))
    rows = np.arange(k // 8)
    d[rows, rng.integers(0, 3, k // 8)] = 0.0  # parallel to a pair of box faces
    d[k // 8 : k // 4, :2] = 0.0  # along z only
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    inside = ellipsoid.centre + rng.uniform(-0.5, 0.5, (k, 3)) * ellipsoid.radii
    outside = rng.uniform(-3.0, 3.0, (k, 3))
    o = np.where((np.arange(k) % 2 == 0)[:, None], inside, outside)
    program = programs.get("testing/pem_texgen_probe.glsl")
    textures = []
    for unit, (name, value) in enumerate((("u_origins", o), ("u_directions", d))):
        rgba = np.concatenate([value, np.zeros((k, 1))], axis=1).astype(np.float32)
        texture = gl_ctx.texture((64, 64), 4, rgba.tobytes(), dtype="f4")
        texture.use(location=unit)
        program[name].value = unit
        textures.append(texture)
    program["u_box_lo"].value = tuple(box.lo)
    program["u_box_hi"].value = tuple(box.hi)
    program["u_ellipsoid_centre"].value = tuple(ellipsoid.centre)
    program["u_ellipsoid_radii"].value = tuple(ellipsoid.radii)
    target = gl_ctx.texture((64, 64), 4, dtype="f4")
    gl_ctx.framebuffer([target]).use()
    gl_ctx.viewport = (0, 0, 64, 64)
    FullscreenPass(gl_ctx).draw(program)
    out = np.frombuffer(target.read(), np.float32).reshape(k, 4).astype(np.float64)
    for got, geometry in ((out[:, 0], box), (out[:, 1], ellipsoid)):
        want = geometry.exit_distance(o, d)
        hit = np.isfinite(want)
        assert np.array_equal(got >= 0, hit)
        assert np.allclose(got[hit], want[hit], rtol=1e-4, atol=1e-4)
    # every ray from inside the ellipsoid leaves it; some from outside miss it
    assert (out[0::2, 1] >= 0).all() and (out[1::2, 1] < 0).any()


def test_a_bake_of_another_scene_or_mesh_is_refused_and_the_previous_one_stays(gl_ctx, room):
    scene, box, ellipsoids = room
    bake = _fake_bake(scene, box, ellipsoids)
    session = RenderSession(scene, ctx=gl_ctx, cube_size=32)
    method = session.method("pem")
    method.show(bake, session.gpu_scene, Path("good.pem"))
    other = _fake_bake(scene, box, ellipsoids)
    other.scene = "studio"
    with pytest.raises(InputFileError, match="a bake of scene 'studio', expected one of 'room'"):
        method.show(other, session.gpu_scene, Path("other.pem"))
    other = _fake_bake(scene, box, ellipsoids)
    other.hull[0] = other.hull[0][:-3]
    with pytest.raises(InputFileError, match=r"baked with .* triangles.*re-bake"):
        method.show(other, session.gpu_scene, Path("mesh.pem"))
    other = _fake_bake(scene, box, ellipsoids)
    other.mesh_checks = other.mesh_checks[:1]
    with pytest.raises(InputFileError, match="1 mesh checks and 2 hull masks for 2 parts"):
        method.show(other, session.gpu_scene, Path("short.pem"))
    other = _fake_bake(scene, box, ellipsoids)
    other.mesh_checks[1] = {**other.mesh_checks[1], "sha256": "0" * 64}
    with pytest.raises(InputFileError, match="'lid' was baked from another mesh"):
        method.show(other, session.gpu_scene, Path("moved.pem"))
    assert method.bake is bake
    session.release()


def test_a_truncated_or_foreign_file_keeps_the_shipped_bake(gl_ctx, tmp_path):
    scene = load_scene("room")
    session = RenderSession(scene, ctx=gl_ctx, cube_size=32)
    method = session.method("pem")
    method.values["coverage"] = "file"  # not the full orbit (test_pem_orbit_gl.py)
    method.prepare(session.gpu_scene)  # the shipped assets/pem/room.pem
    shipped = method.bake
    assert shipped is not None and shipped.scene == "room"
    data = shipped_bake("room").read_bytes()
    (tmp_path / "cut.pem").write_bytes(data[: len(data) // 2])
    (tmp_path / "v9.pem").write_bytes(data[:8] + (9).to_bytes(4, "little") + data[12:])
    for name, message in (("cut.pem", "truncated"), ("v9.pem", "version 9")):
        method.values["pem"] = str(tmp_path / name)
        with pytest.raises(InputFileError, match=message) as caught:
            method.prepare(session.gpu_scene)
        assert len(str(caught.value).splitlines()) == 1
        assert method.bake is shipped and method.values["pem"] == ""
    # a scene without a bake shows the static EM; a bad name there goes back to that too
    studio = RenderSession(load_scene("studio"), ctx=gl_ctx, cube_size=32)
    other = studio.method("pem")
    studio.render_offscreen(other, (32, 32))
    assert other.bake is None and "showing the static EM" in other.status_line()
    other.values["pem"] = str(tmp_path / "cut.pem")
    with pytest.raises(InputFileError, match="truncated"):
        other.prepare(studio.gpu_scene)
    assert other.values["pem"] == "" and other.bake is None
    studio.render_offscreen(other, (32, 32))  # and draws again
    studio.release()
    # turned after the bake (the viewer's rotation or turntable): the status says so
    session.render_offscreen(method, (32, 32))
    assert "views x 2 parts resident" in method.status_line()
    for node in scene.reflectors():
        node.transform.rotation = (0.0, 30.0, 0.0)
    session.gpu_scene.refresh_transforms()
    session.render_offscreen(method, (32, 32))
    assert "moved or turned since its bake" in method.status_line()
    session.release()


def test_figures_of_the_shipped_bake(tmp_path, capsys):
    from envstudio.cli import main
    from envstudio.io.images import read_image

    off = tmp_path / "off.png"
    argv = ["figure", "pem-offmanifold", "--scene", "room", "--size", "128x128", "-o", str(off)]
    assert main(argv) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if "°):" in line]
    assert len(rows) == 5  # three midway views, 10° and 20° above the arc
    for line in rows:  # seed 003 Figures 6-7: the layered PEM is best at every view
        db = {
            m: float(line.split(f" {m} ")[1].split(" dB")[0])
            for m in ("layered", "sphere", "static")
        }
        assert db["layered"] > max(db["sphere"], db["static"]) + 1.0, line
        if "midway" in line:
            assert db["sphere"] > db["static"], line
    maps = tmp_path / "maps.png"
    assert main(["figure", "pem-maps", "--scene", "room", "-o", str(maps)]) == 0
    for path in (off, maps):
        image = read_image(path)
        assert image.shape[0] > 200 and image.std() > 0.05


def test_a_bake_under_another_environment_plays_with_a_warning(gl_ctx, room, capsys):
    """The bake records its environment's checksum; the scene's own plays quietly."""
    scene, box, ellipsoids = room
    session = RenderSession(scene, ctx=gl_ctx, cube_size=32)
    method = session.method("pem")
    own = _fake_bake(scene, box, ellipsoids)
    own.parameters = {**own.parameters, "environment": scene.environment.checksum()}
    method.show(own, session.gpu_scene, Path("own.pem"))
    session.render_offscreen(method, (R, R))
    assert "another environment" not in method.status_line()
    other = _fake_bake(scene, box, ellipsoids)
    other.parameters = {**other.parameters, "environment": "0" * 64}
    method.show(other, session.gpu_scene, Path("other.pem"))
    session.render_offscreen(method, (R, R))
    assert "other.pem was baked under another environment than interior" in method.status_line()
    assert "another environment" in capsys.readouterr().err
    session.release()
