"""The full-orbit PEM (issue 31): views baked on demand, a few resident, resumable.

The orbit's views are baked at tiny sizes with the CPU lookups (in this process) on
a 30° grid; what is checked is the machinery: which views are baked, that playback
from resident slots is the playback of the same maps as a bake file, and that a
background bake stopped midway leaves only whole parts and resumes.
"""

import time
from pathlib import Path

import numpy as np
import pytest

from envstudio.engine.session import RenderSession
from envstudio.io.scene_file import load_scene
from envstudio.methods.pem.atlas import flat_maps
from envstudio.methods.pem.bake.bake import neighbours
from envstudio.methods.pem.bake.orbit import OrbitStore
from envstudio.methods.pem.bake.pem_file import PemBake
from envstudio.methods.pem.blending import ptm_blend
from envstudio.methods.pem.orbit_job import OrbitBakeJob
from envstudio.methods.pem.resident import ResidentViews

TINY = {"size": 16, "samples": 1, "em_size": 8, "ptm": False}
TINY_PTM = {**TINY, "ptm": True}
STEP = (30.0, 30.0)
R = 40


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("ENVSTUDIO_CACHE_DIR", str(tmp_path))
    return tmp_path


def _random_maps(shell, view):
    rng = np.random.default_rng(view)
    return {
        m: [rng.uniform(0.0, 1.0, level.shape[1:]).astype(np.float32) for level in levels]
        for m, levels in shell.maps.items()
    }


def _grid_file(store, azimuths, elevations):
    """The orbit's views at these azimuth and elevation indices as a grid bake file."""
    shell, count = store.shell(), len(store.space["azimuths"])
    views = [e * count + a for e in elevations for a in azimuths]
    maps = [store.load(v) for v in views]
    angles = [store.space["azimuths"][a] for a in azimuths]
    grid = {
        **store.space,
        "azimuths": list(np.unwrap(angles, period=360.0)),
        "elevations": [store.space["elevations"][e] for e in elevations],
    }
    del grid["closed"]
    return PemBake(
        scene="room",
        view_space=grid,
        parts=shell.parts,
        parameters=shell.parameters,
        maps={
            m: [np.stack(level) for level in zip(*(v[m] for v in maps), strict=True)]
            for m in maps[0]
        },
        hull=shell.hull,
        mesh_checks=shell.mesh_checks,
        psnr={},
        playback_psnr={},
        cameras=shell.cameras[views],
        box=shell.box,
        origins=shell.origins,
        ellipsoids=shell.ellipsoids,
    )


def test_resident_slots_hold_exactly_the_views_asked_for_least_recent_out(gl_ctx, cache):
    shell = OrbitStore("room", None, STEP, parameters=TINY).shell()
    resident = ResidentViews(gl_ctx, shell, slots=3)
    load = lambda v: _random_maps(shell, v)  # noqa: E731
    assert resident.slots([0, 1], load) == [0, 1] and resident.slots([2], load) == [2]
    assert resident.slots([1, 3], load) == [1, 0]  # 0 was the least recently used
    assert resident.slots([7], lambda v: None) is None  # not baked: nothing moved
    texels = len(flat_maps([a[None] for a in _random_maps(shell, 0)["distant"]]))
    for model, texture in resident.atlases.items():
        atlas = np.frombuffer(texture.read(), np.float32).reshape(-1, 4)
        for view, slot in resident.resident.items():
            want = flat_maps([a[None] for a in _random_maps(shell, view)[model]])
            assert np.array_equal(atlas[slot * texels : (slot + 1) * texels], want)
    resident.release()


def test_the_orbit_bakes_what_a_frame_blends_and_plays_it_as_a_bake_file_would(gl_ctx, cache):
    scene = load_scene("room")
    session = RenderSession(scene, ctx=gl_ctx, cube_size=32)
    method = session.method("pem")
    method.orbit_store = lambda source, *_: OrbitStore(source, None, STEP, parameters=TINY)
    method.values.update({"kd": 0.0, "fresnel_layer": False})
    session.renderer.display["background"] = False
    session.camera.azimuth, session.camera.elevation = 25.0 + 12.0, 18.0 + 9.0  # in a cell
    session.render_offscreen(method, (R, R))
    orbit_image = session.read_hdr().astype(np.float64)
    store, blend = method._loaded.orbit, method.last_blend
    assert len(blend.views) == 4 and store.done() == set(blend.views)
    assert f"4 of {store.total} views baked" in method.status_line()
    views_folder = store.view_path(0).parent
    stamps = {p: p.stat().st_mtime_ns for p in views_folder.iterdir()}
    session.render_offscreen(method, (R, R))  # baked once: nothing is baked again
    assert {p: p.stat().st_mtime_ns for p in views_folder.iterdir()} == stamps
    # the same four views' maps as a 2 x 2 grid bake file, played the file's way
    count = len(store.space["azimuths"])
    a0, e0 = 0, int(np.searchsorted(store.space["elevations"], 27.0)) - 1  # the cell's corner
    a1, e1 = a0 + 1, e0 + 1
    views = [e * count + a for e in (e0, e1) for a in (a0, a1)]
    assert set(views) == set(blend.views)
    bake = _grid_file(store, (a0, a1), (e0, e1))
    # a cell whose lower views are under the floor (they see no reflector): the blend keeps
    # the upper two, their weights scaled to sum to 1
    session.camera.elevation = 3.0  # between the rows at -12 and 18 degrees
    session.render_offscreen(method, (R, R))
    rows = {v // count: store.sees_reflector(v) for v in method.last_blend.views}
    upper = int(np.searchsorted(store.space["elevations"], 3.0))
    assert rows == {upper: True} and np.isclose(sum(method.last_blend.weights), 1.0)
    assert not any(store.sees_reflector(v) for v in store.done() if v // count == upper - 1)
    session.camera.elevation = 27.0
    method.values["coverage"] = "file"
    method.show(bake, session.gpu_scene, Path("grid.pem"))
    session.render_offscreen(method, (R, R))
    file_image = session.read_hdr().astype(np.float64)
    covered = np.abs(orbit_image).sum(axis=-1) > 0
    assert covered.sum() > 100
    assert np.abs(file_image - orbit_image).max() <= 1e-6 * np.abs(orbit_image).max()
    session.release()


def test_the_orbits_ptm_fits_the_views_around_the_camera_that_saw_the_reflector(gl_ctx, cache):
    """``em_model=ptm`` on the full orbit: its 4 × 4 window is baked, the row under the floor
    leaves the fit, and the image is the PTM playback of those views as a bake file."""
    session = RenderSession(load_scene("room"), ctx=gl_ctx, cube_size=32)
    method = session.method("pem")
    method.orbit_store = lambda source, *_: OrbitStore(source, None, STEP, parameters=TINY_PTM)
    method.values.update({"kd": 0.0, "fresnel_layer": False, "em_model": "ptm"})
    session.renderer.display["background"] = False
    session.camera.azimuth, session.camera.elevation = 37.0, 27.0  # the cell 25–55°, 18–48°
    session.render_offscreen(method, (R, R))
    ptm_image = session.read_hdr().astype(np.float64)
    store, blend = method._loaded.orbit, method.last_blend
    count = len(store.space["azimuths"])
    rows = sorted({v // count for v in blend.views})
    window = ptm_blend(store.space, session.camera.position)  # all 16, the row below too
    assert store.done() >= set(window.views) and len(window.views) == 16
    assert len(blend.views) == 12 and len(rows) == 3  # the row at −12° saw nothing
    assert not any(store.sees_reflector(v) for v in set(window.views) - set(blend.views))
    assert any(w < 0 for w in blend.weights) and np.isclose(sum(blend.weights), 1.0)
    columns = [v % count for v in blend.views[:4]]  # the window's order: across 360°
    assert columns[0] == count - 1
    method.values["em_model"] = "layered"
    session.render_offscreen(method, (R, R))
    layered_image = session.read_hdr().astype(np.float64)
    covered = np.abs(ptm_image).sum(axis=-1) > 0
    assert covered.sum() > 100 and np.abs(layered_image - ptm_image)[covered].mean() > 1e-3
    method.values.update({"coverage": "file", "em_model": "ptm"})
    method.show(_grid_file(store, columns, rows), session.gpu_scene, Path("window.pem"))
    session.render_offscreen(method, (R, R))
    file_image = session.read_hdr().astype(np.float64)
    assert np.abs(file_image - ptm_image).max() <= 1e-5 * np.abs(ptm_image).max()
    session.release()


def test_a_background_bake_stopped_midway_keeps_whole_views_and_resumes(cache):
    store = OrbitStore("room", None, STEP, parameters=TINY)
    job = OrbitBakeJob(store, "room")
    camera = load_scene("room").camera
    job.request(camera, [0])
    deadline = time.monotonic() + 60.0
    while not job.done() and time.monotonic() < deadline:
        time.sleep(0.2)
    job.stop()
    done = store.done()
    assert done and not job.running
    names = sorted(p.name for p in store.view_path(0).parent.iterdir())
    assert names == [store.view_path(v).name for v in sorted(done)]  # no half-written file
    assert all(store.load(v) is not None for v in done)
    first = store.view_path(sorted(done)[0])
    stamp = first.stat().st_mtime_ns
    again = OrbitBakeJob(store, "room")
    again.request(camera, [])
    assert again._order and not set(again._order) & done  # only the views still missing
    again.stop()
    assert first.stat().st_mtime_ns == stamp


def test_an_orbit_under_a_replaced_environment_is_refused_and_auto_plays_the_file(gl_ctx, cache):
    """The orbit bakes the scene file's environment: replaced in place, orbit=... refuses in one
    line (and again without rebuilding), auto falls back to the shipped arc bake."""
    from envstudio.errors import InputFileError
    from envstudio.io.images import read_image
    from envstudio.resources import asset_root
    from envstudio.scene.environment import Environment

    session = RenderSession(load_scene("room"), ctx=gl_ctx, cube_size=32)
    method = session.method("pem")
    method.orbit_store = lambda source, *_: OrbitStore(source, None, STEP, parameters=TINY)
    method.prepare(session.gpu_scene)
    assert method.orbit is not None
    night = asset_root() / "hdr" / "night.exr"
    session.gpu_scene.set_environment(Environment(read_image(night)[::8, ::8], night))
    method.values["coverage"] = "orbit"
    for _ in range(2):
        with pytest.raises(InputFileError, match="environment was replaced") as info:
            method.prepare(session.gpu_scene)
        assert "\n" not in str(info.value)
    method.values["coverage"] = "auto"
    method.prepare(session.gpu_scene)
    assert method.orbit is None and method.bake.views == 6  # the shipped arc
    session.release()


def test_an_orbit_with_the_ptm_is_another_orbit_and_one_without_keeps_its_folder(cache):
    """The bake's key does not name the models, so an orbit baked before the PTM must not
    pass for one with it (its views would lack the maps the PTM plays)."""
    plain = OrbitStore("room", None, STEP, parameters=TINY)
    with_ptm = OrbitStore("room", None, STEP, parameters=TINY_PTM)
    assert plain.plan.key == with_ptm.plan.key and plain.key == plain.plan.key
    assert plain.folder.name == f"orbit-room-{plain.plan.key[:16]}"  # the folder of before
    assert with_ptm.folder != plain.folder and with_ptm.key != plain.key


def test_a_coupled_orbit_draws_each_view_towards_its_neighbours_plain_maps(cache):
    """``orbit_coupling``: the views and their four neighbours (across 360° too) are baked
    without coupling, in the plain orbit's own cache; each stored view is then nearer the
    mean of its neighbours' plain maps than its own plain maps are (one coupled pass)."""
    coupled = OrbitStore("room", None, STEP, parameters={**TINY, "coupling": 1.0})
    plain = coupled.independent
    assert plain.folder == OrbitStore("room", None, STEP, parameters=TINY).folder
    count = len(coupled.space["azimuths"])
    row = coupled.space["elevations"].index(18.0)  # the scene camera's row
    views = [row * count, row * count + 1]
    coupled.bake(views, workers=0)
    near = neighbours(coupled.space)
    assert row * count + count - 1 in near[views[0]]  # across 360°
    assert plain.done() >= set(views) | {n for v in views for n in near[v]}
    assert coupled.done() == set(views)
    for view in views:
        seen = [n for n in near[view] if np.isfinite(plain.result(n)["psnr_distant"][0])]
        mean = np.mean([plain.result(n)["distant_0"][0] for n in seen], axis=0)
        alone = np.abs(plain.result(view)["distant_0"][0] - mean).mean()
        drawn = np.abs(coupled.result(view)["distant_0"][0] - mean).mean()
        assert len(seen) >= 3 and drawn < 0.7 * alone
