"""The .pem file and the bake job (seed 003 §3, §4): bake/pem/pem_file.py, bake/pem/bake.py."""

from __future__ import annotations

import json

import numpy as np
import pytest

from envstudio.bake.pem import SceneTracer
from envstudio.bake.pem.bake import parts_folder, run_bake
from envstudio.bake.pem.infer import infer_distant
from envstudio.bake.pem.pem_file import ARRAYS, _checksum, load_pem
from envstudio.bake.pem.views import arc_views
from envstudio.cli import main
from envstudio.errors import InputFileError
from envstudio.io.scene_file import load_scene

TINY = {"size": 32, "samples": 2, "em_size": 4, "workers": 0}


def _arc(count):
    return lambda camera: arc_views(camera, count, 5.0)


@pytest.fixture(scope="module")
def baked(tmp_path_factory):
    path = tmp_path_factory.mktemp("pem") / "room.pem"
    report = run_bake("room", _arc(2), path, **TINY)
    return path, report


def test_round_trip_equals_inference(baked):
    path, report = baked
    assert report.baked == [0, 1] and not parts_folder(path).exists()
    bake = load_pem(path)
    scene = load_scene("room")
    tracer = SceneTracer(scene)
    assert bake.parts == tracer.part_names and bake.distant.shape == (2, 2, 6, 4, 4, 3)
    assert bake.view_space == arc_views(scene.camera, 2, 5.0).describe()
    for v, camera in enumerate(arc_views(scene.camera, 2, 5.0).cameras()):
        view = tracer.trace(camera, 32, 2, seed=v)
        for p in range(len(tracer.part_names)):
            em = infer_distant(scene, tracer, view, p, size=4)
            np.testing.assert_array_equal(bake.distant[v, p], em.em.astype(np.float32))
            np.testing.assert_array_equal(bake.seen[v, p], em.seen)
            assert bake.psnr[v, p] == em.psnr
            np.testing.assert_array_equal(bake.origins[p], em.origin)
    np.testing.assert_array_equal(bake.cameras[:, 0], [scene.camera.azimuth + d for d in (0, 5)])
    assert np.all(bake.ellipsoids[:, 1] > 0) and np.all(bake.box[1] > bake.box[0])


def _rewrite(src, dst, header_edit=None, array_edit=None, rehash=False):
    with np.load(src) as data:
        header = json.loads(str(data["header"]))
        arrays = {k: np.array(data[k]) for k in ARRAYS}
    if header_edit:
        header_edit(header)
    if array_edit:
        array_edit(arrays)
    if rehash:
        header["checksum"] = _checksum(arrays, header)
    np.savez(dst, header=np.array(json.dumps(header)), **arrays)
    return dst


def _refused(path, words):
    with pytest.raises(InputFileError) as info:
        load_pem(path)
    message = str(info.value)
    assert "\n" not in message and words in message, message


def test_corrupt_files_are_refused_with_one_line(baked, tmp_path):
    path, _ = baked
    data = path.read_bytes()
    truncated = tmp_path / "truncated.pem"
    truncated.write_bytes(data[: len(data) // 2])
    _refused(truncated, "not a readable .pem")

    def bump(arrays):
        arrays["distant"][0, 0, 0, 0, 0, 0] += 1.0

    _refused(_rewrite(path, tmp_path / "t.npz", array_edit=bump), "checksum mismatch")

    def version(header):
        header["version"] = 99

    _refused(_rewrite(path, tmp_path / "v.npz", header_edit=version), "version 99")

    def drop(arrays):
        for k in ("distant", "seen", "psnr", "iterations", "cameras"):
            arrays[k] = arrays[k][:1]

    _refused(_rewrite(path, tmp_path / "m.npz", array_edit=drop, rehash=True), "views are missing")
    not_pem = tmp_path / "x.pem"
    not_pem.write_text("hello")
    _refused(not_pem, "not a readable .pem")


def test_resumed_bake_skips_finished_views(baked, tmp_path, monkeypatch):
    reference, _ = baked
    out = tmp_path / "resumed.pem"

    def stop(index, result):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_bake("room", _arc(2), out, on_view=stop, **TINY)
    assert not out.exists()
    assert [p.name for p in parts_folder(out).iterdir()] == ["view-00000.npz"]

    traced = []
    original = SceneTracer.trace

    def counting(self, camera, *args, **kw):
        traced.append(camera.azimuth)
        return original(self, camera, *args, **kw)

    monkeypatch.setattr(SceneTracer, "trace", counting)
    report = run_bake("room", _arc(2), out, **TINY)
    assert report.reused == [0] and report.baked == [1] and len(traced) == 1
    assert not parts_folder(out).exists()
    a, b = load_pem(out), load_pem(reference)
    assert a.header["checksum"] == b.header["checksum"]
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_parts_of_another_bake_are_not_reused(tmp_path):
    out = tmp_path / "stale.pem"

    def stop(index, result):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_bake("room", _arc(2), out, on_view=stop, **TINY)
    report = run_bake("room", _arc(2), out, **{**TINY, "samples": 1})
    assert report.reused == [] and report.baked == [0, 1]


@pytest.mark.parametrize("runner", [["--workers", "2"], ["--dask"]])
def test_cli_bakes_on_a_pool(tmp_path, capsys, runner):
    out = tmp_path / "cli.pem"
    argv = ["bake", "pem", "--scene", "room", "--views", "2", "--step", "5", "--size", "32"]
    argv += ["--samples", "2", "--em-size", "4", *runner, "-o", str(out)]
    assert main(argv) == 0
    assert "2 views × 2 parts" in capsys.readouterr().out
    assert load_pem(out).views == 2


def test_local_dask_cluster_bakes_the_same_file(baked, tmp_path):
    # distributed is pinned in requirements.lock: a missing install must fail, not skip
    out = tmp_path / "dask.pem"
    report = run_bake("room", _arc(2), out, scheduler="local", **TINY)
    assert sorted(report.baked) == [0, 1] and not parts_folder(out).exists()
    checksums = []
    for path in (baked[0], out):
        with np.load(path) as data:
            checksums.append(json.loads(str(data["header"]))["checksum"])
    assert checksums[0] == checksums[1]
    pool, dask = load_pem(baked[0]), load_pem(out)
    for name in ("distant", "seen", "psnr", "iterations"):
        np.testing.assert_array_equal(getattr(dask, name), getattr(pool, name))


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--views", "0"], "--views 0"),
        (["--views", "-3"], "--views -3"),
        (["--step", "0"], "--step 0"),
        (["--step", "-1"], "--step -1"),
        (["--views", "400", "--step", "1"], "coincide"),
        (["--size", "2"], "--size 2"),
        (["--scene", "nowhere"], "no such scene"),
        (["-o", "missing/dir/out.pem"], "does not exist"),
    ],
)
def test_bad_input_is_one_line(tmp_path, capsys, monkeypatch, extra, words):
    monkeypatch.chdir(tmp_path)
    argv = ["bake", "pem", "--scene", "room", "--views", "2", "-o", "out.pem"]
    if "--scene" in extra:
        argv[3] = extra[1]
        extra = []
    elif "-o" in extra:
        argv[-1] = extra[1]
        extra = []
    assert main(argv + extra) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and words in err, err
    assert not any(tmp_path.iterdir())
