"""The saved-reference cache: keyed by the estimator's shaders, within its size limit."""

from __future__ import annotations

import os

import numpy as np
import pytest

from envstudio.core.metrics import flip, psnr
from envstudio.engine.grid_view import tile_layout
from envstudio.engine.session import RenderSession
from envstudio.errors import ParameterError
from envstudio.gpu.programs import read_shader
from envstudio.measure import ground_truth_cache
from envstudio.measure.cached_reference import CachedReferences
from envstudio.measure.compare import method_classes, plan_parameters, run_comparison
from envstudio.measure.ground_truth_cache import cache_limit_bytes, load_state, prune, save_state
from envstudio.measure.matching import GlossinessLink
from envstudio.measure.reference_runs import MONTE_CARLO
from envstudio.methods.reference import method as reference_method
from envstudio.scene.environment import Environment
from envstudio.ui.grid import GridMetrics, GridState, tile_label
from test_render_gl import sphere_scene

MB = 2**20


def write(path, megabytes: float, mtime: float) -> None:
    path.write_bytes(b"\0" * int(megabytes * MB))
    os.utime(path, (mtime, mtime))


def test_prune_deletes_the_least_recently_used_until_under_the_limit(tmp_path):
    for i in range(5):
        write(tmp_path / f"{i}.npz", 1.0, 1000.0 + i)
    (tmp_path / "notes.txt").write_bytes(b"\0" * 5 * MB)  # not a saved accumulation
    deleted = prune(tmp_path, tmp_path / "4.npz", int(2.5 * MB))
    assert [p.name for p in deleted] == ["0.npz", "1.npz", "2.npz"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["3.npz", "4.npz", "notes.txt"]


def test_prune_never_deletes_the_file_just_written(tmp_path):
    write(tmp_path / "old.npz", 3.0, 1000.0)
    write(tmp_path / "other.npz", 1.0, 2000.0)
    assert prune(tmp_path, tmp_path / "old.npz", MB // 2) == [tmp_path / "other.npz"]
    assert (tmp_path / "old.npz").exists()


def test_loading_a_state_makes_it_the_last_to_go(tmp_path, monkeypatch):
    state = {"sum": np.ones((64, 64, 4), np.float32)}
    first, second, third = (tmp_path / f"{name}.npz" for name in ("first", "second", "third"))
    monkeypatch.setenv("ENVSTUDIO_CACHE_MAX_MB", "1000")
    for i, path in enumerate((first, second)):
        save_state(path, state)
        os.utime(path, (1000.0 + i, 1000.0 + i))
    np.testing.assert_array_equal(load_state(first)["sum"], state["sum"])
    size = first.stat().st_size
    monkeypatch.setenv("ENVSTUDIO_CACHE_MAX_MB", str(2.5 * size / MB))
    save_state(third, state)  # three files over a limit of two and a half: the oldest goes
    assert first.exists() and third.exists() and not second.exists()


@pytest.mark.parametrize("value", ["lots", "-1", "nan"])
def test_a_bad_limit_is_one_line_naming_the_variable(monkeypatch, value):
    monkeypatch.setenv("ENVSTUDIO_CACHE_MAX_MB", value)
    with pytest.raises(ParameterError, match=f"ENVSTUDIO_CACHE_MAX_MB='{value}': expected"):
        cache_limit_bytes()


def test_the_key_follows_the_estimators_shaders_and_their_includes_only(gl_ctx, monkeypatch):
    session = RenderSession(sphere_scene(Environment.constant([1.0, 1.0, 1.0])), ctx=gl_ctx)
    reference = session.method("reference")

    def key_with_edited(edited: str | None):
        def read(name: str) -> str:
            return read_shader(name) + ("// edited\n" if name == edited else "")

        monkeypatch.setattr(reference_method, "read_shader", read)
        return ground_truth_cache.cache_path(session, reference, (32, 32))

    base = key_with_edited(None)
    for included in ("common/sobol.glsl", "reference/trace.glsl", "reference/merge_batch.glsl"):
        assert key_with_edited(included) != base, included
    for unrelated in ("common/colormap.glsl", "kautz/kautz.glsl", "common/spheremap.glsl"):
        assert key_with_edited(unrelated) == base, unrelated
    session.release()


def test_the_key_leaves_out_only_when_to_stop_and_how_batches_are_drawn(gl_ctx):
    session = RenderSession(sphere_scene(Environment.constant([1.0, 1.0, 1.0])), ctx=gl_ctx)
    reference = session.method("reference")
    base = ground_truth_cache.cache_path(session, reference, (32, 32))
    reference.values.update({"max_samples": 5, "tolerance": 0.01, "samples_per_draw": 2})
    assert ground_truth_cache.cache_path(session, reference, (32, 32)) == base
    for name, value in (("samples", 4), ("kd", 0.5), ("sequence", "random")):
        default = reference.values[name]
        reference.values[name] = value
        assert ground_truth_cache.cache_path(session, reference, (32, 32)) != base, name
        reference.values[name] = default
    session.release()


def _flip_a_byte(path):
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x40
    path.write_bytes(bytes(data))


def _checksummed_elsewhere(path):
    """A valid archive whose arrays were changed after its checksum was taken."""
    with np.load(path) as data:
        arrays = {name: data[name] for name in data.files}
    arrays["sum"] = arrays["sum"] + 1.0
    with open(path, "wb") as handle:
        np.savez(handle, **arrays)


@pytest.mark.parametrize(
    "corrupt",
    [
        pytest.param(lambda p: p.write_bytes(p.read_bytes()[: len(p.read_bytes()) // 2]), id="cut"),
        pytest.param(_flip_a_byte, id="bit-flip"),
        pytest.param(_checksummed_elsewhere, id="edited"),
        pytest.param(lambda p: p.write_bytes(b""), id="empty"),
        pytest.param(lambda p: (p.unlink(), p.mkdir()), id="folder"),
    ],
)
def test_a_saved_state_that_does_not_load_is_one_note_and_discarded(tmp_path, capsys, corrupt):
    path = tmp_path / "reference" / "key.npz"
    state = {"sum": np.arange(48, dtype=np.float32).reshape(4, 3, 4), "batches": np.int64(3)}
    save_state(path, state)
    loaded = load_state(path)
    assert set(loaded) == set(state) and np.array_equal(loaded["sum"], state["sum"])
    corrupt(path)
    capsys.readouterr()
    assert load_state(path) is None
    notes = capsys.readouterr().err.splitlines()
    assert len(notes) == 1 and notes[0].startswith(f"envstudio: note: {path}: unreadable")
    assert not path.exists()  # discarded: the next save writes a fresh one
    save_state(path, state)
    assert np.array_equal(load_state(path)["sum"], state["sum"])


def _gradient() -> Environment:
    """A 32 x 16 lat-long map, bright at the top and coloured by longitude."""
    v, u = np.mgrid[0:16, 0:32].astype(np.float32)
    image = np.dstack([1.0 + u / 8.0, 4.0 * (1.0 - v / 16.0) ** 2, 0.5 + v / 16.0])
    return Environment(image.astype(np.float32))


def test_the_grid_finds_compares_reference_and_measures_a_tile_as_compare_did(gl_ctx):
    """Issue 29: a reference ``compare`` saved is found for the viewer's tiles at the same
    camera (kautz at the b matched to N; hwconv at N and mirror share its model's reference)
    and the tile's PSNR and FLIP against it equal core/metrics' on compare's own images."""
    size, exponent = (32, 32), 100.0
    session = RenderSession(sphere_scene(_gradient(), rings=16), ctx=gl_ctx)
    plan = plan_parameters(
        method_classes(["kautz"]), ["trace=false", "max_samples=8", f"phong_exponent={exponent:g}"]
    )
    comparison = run_comparison(  # a saved Monte Carlo accumulation, what the grid reads
        session, ["kautz"], size, plan, frames=1, warmup=0, cache=True, reference_kind=MONTE_CARLO
    )
    session.release()

    viewer = RenderSession(sphere_scene(_gradient(), rings=16), ctx=gl_ctx)  # the window's session
    hub = viewer.method("reference")
    hub.values["trace"] = False  # the reference panel as the comparison had it
    tiles = [viewer.method(name) for name in ("hwconv", "kautz", "mirror", "reference")]
    tiles[0].values["phong_exponent"] = exponent
    cube = viewer.gpu_scene.cube_size
    GlossinessLink().follow(tiles, tiles[0], hub, cube)
    cached = CachedReferences(gl_ctx, viewer.programs, type(hub))
    found = cached.find(viewer, hub, tiles, hub, cube)
    assert sorted(found) == ["hwconv", "kautz", "mirror"]  # one reference for the model
    assert {f.path for f in found.values()} == {ground_truth_cache.cache_path(session, hub, size)}
    assert found["kautz"].size == size

    display = viewer.renderer.display.as_dict()
    truth, mask = comparison.reference.display, comparison.mask
    for result in comparison.results:
        numbers = cached.measure(viewer, viewer.method(result.name), found[result.name], display)
        assert numbers.psnr_db == pytest.approx(psnr(result.display, truth, mask), rel=1e-6)
        assert numbers.flip == pytest.approx(flip(result.display, truth, mask), rel=1e-5)
        assert numbers.psnr_db == pytest.approx(result.metrics.psnr_db, rel=1e-6)
        assert "8 spp" in numbers.reference

    # the grid: looked up once the view stays still, then one tile a step, labelled
    clock = iter(range(100))
    metrics = GridMetrics(viewer.renderer, "reference", clock=lambda: float(next(clock)))
    state = GridState()
    state.enter()
    state.tiles = tile_layout(["hwconv", "kautz", "mirror"], (0, 0, 96, 32))
    shown = {name: viewer.method(name) for name in ("hwconv", "kautz", "mirror")}
    for _ in range(5):  # a change, the look-up, three tiles
        metrics.update(state, shown, viewer, hub, None)
    kautz = state.numbers["kautz"]
    assert (kautz.psnr_db, kautz.against) == (numbers.psnr_db, "cached 32×32")
    assert all(state.numbers[name].psnr_db is not None for name in shown)
    assert tile_label(state.tiles[1], kautz).endswith("(cached 32×32)")
    assert "compare saved at this camera (phong 32×32, N = 100: 8 spp" in state.metrics_note

    viewer.camera.orbit(10.0, 0.0)  # another camera: the numbers go, no reference there
    metrics.update(state, shown, viewer, hub, None)
    assert all(state.numbers[name].psnr_db is None for name in shown)
    assert cached.find(viewer, hub, tiles, hub, cube) == {}
    for _ in range(2):
        metrics.update(state, shown, viewer, hub, None)
    assert "no reference saved by compare at this camera" in state.metrics_note
    metrics.release()
    cached.release()
    viewer.release()
