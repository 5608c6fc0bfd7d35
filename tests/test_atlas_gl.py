"""``envstudio atlas``: its outputs, a cell against ``compare``, resume, the page in Chromium,
and the same cells from a Dask LocalCluster as from the process pool."""

import json
import re
import shutil
import subprocess

import numpy as np
import pytest

from envstudio.cli import main
from envstudio.io.images import read_image, write_image
from envstudio.measure import exact_lobes
from envstudio.measure.atlas import pool, sessions
from envstudio.measure.atlas.grid import AtlasGrid
from envstudio.measure.atlas.page import pareto_front
from envstudio.measure.atlas.run import run_atlas
from envstudio.resources import asset_root

#: A reference that stops at 32 spp: deterministic, so every run finds the same numbers.
FAST = ["--size", "32x32", "--ssaa", "2", "--param", "max_samples=32", "--time-limit", "600"]
NUMBERS = ("approximation_error", "scene_error", "scene_only_error", "psnr_db", "flip")


def atlas(out, *extra):
    scene = ["--envs", "sunset", "--meshes", "bunny"]
    return main(["atlas", *scene, *FAST, "--out", str(out), *extra])


def grid(**changes) -> AtlasGrid:
    values = dict(
        methods=("mirror", "kautz"),
        envs=("sunset",),
        meshes=("sphere",),
        exponents=(50.0,),
        kds=(0.0,),
        size=(32, 32),
        cameras=1,
        time_limit=600.0,
        ssaa=2,
        params=("max_samples=32",),
    )
    return AtlasGrid(**(values | changes))


def test_an_atlas_writes_every_output_and_its_cells_are_compare_s_numbers(tmp_path, capsys):
    out = tmp_path / "atlas"
    assert atlas(out, "--methods", "mirror,kautz", "--exponents", "100") == 0
    for name in ("index.html", "atlas.json", "atlas.csv", "atlas.png"):
        assert (out / name).stat().st_size > 0
    document = json.loads((out / "atlas.json").read_text())
    cells = {row["method"]: row for row in document["cells"]}
    assert set(cells) == {"mirror", "kautz"} and all(r["error"] is None for r in cells.values())
    assert len((out / "atlas.csv").read_text().splitlines()) == 3
    assert cells["mirror"]["cost_ratio"] == 1.0 and cells["kautz"]["cost_ratio"] > 0
    for row in cells.values():
        assert all((out / "cells" / row[k]).exists() for k in ("image", "heat_map"))

    hdr = asset_root() / "hdr" / "sunset.exr"
    mesh = asset_root() / "mesh" / "bunny.ply"
    same = ["--env", str(hdr), "--mesh", str(mesh), "--param", "phong_exponent=100"]
    args = ["--methods", "mirror,kautz", "--param", "kd=0", "--frames", "5", "--warmup", "1"]
    assert main(["compare", *FAST, *same, *args, "--out", str(tmp_path / "cmp")]) == 0
    methods = json.loads((tmp_path / "cmp" / "compare.json").read_text())["methods"]
    for name, row in cells.items():
        theirs = methods[name]
        assert row["scene_error"] == pytest.approx(theirs["scene_error"], rel=1e-6)
        assert row["psnr_db"] == pytest.approx(theirs["psnr_db"], rel=1e-6)
        assert row["approximation_error"] == pytest.approx(
            theirs["approximation"]["median_relative_error"], rel=1e-6
        )
    capsys.readouterr()


def test_an_interrupted_atlas_measures_only_the_rest(tmp_path, monkeypatch):
    wide = grid(exponents=(20.0, 200.0))
    calls = []
    measure = pool.measure_task

    def interrupted_after_one(task):
        if calls:
            raise KeyboardInterrupt
        calls.append(task)
        return measure(task)

    monkeypatch.setattr(pool, "measure_task", interrupted_after_one)
    with pytest.raises(KeyboardInterrupt):
        run_atlas(wide, tmp_path)
    monkeypatch.setattr(pool, "measure_task", measure)
    first = next((tmp_path / "cells").glob("*.json"))
    kept = first.read_text()
    result = run_atlas(wide, tmp_path)
    assert result.measured == 2 and len(result.rows) == 4  # the second scene's two cells
    assert first.read_text() == kept


def test_scenes_of_one_map_share_a_session_and_measure_what_fresh_ones_do(tmp_path, monkeypatch):
    """What is derived from the map alone (Banks' 3D map, the pyramid of its
    exact reference) is built for the first scene and serves the next: the numbers are a
    fresh session's, cell by cell."""
    pyramids = []

    class Counted(exact_lobes.PyramidTextures):
        def __init__(self, *args):
            pyramids.append(args)
            super().__init__(*args)

    monkeypatch.setattr(exact_lobes, "PyramidTextures", Counted)
    sunset = read_image(asset_root() / "hdr" / "sunset.exr")  # 8 x 8 texels to one: quick checks
    small = sunset.reshape(64, 8, 128, 8, 3).mean(axis=(1, 3))
    env = str(write_image(tmp_path / "small.exr", small))
    g = grid(methods=("mirror", "banks"), envs=(env,), meshes=("sphere", "knot"))
    made = sessions.KEPT.made
    monkeypatch.setenv("ENVSTUDIO_CACHE_DIR", str(tmp_path / "cache"))  # nothing read back
    shared = run_atlas(g, tmp_path / "shared").rows
    assert sessions.KEPT.made == made + 1 and len(pyramids) == 1
    # the second scene alone, in a session of its own (run_atlas released the kept one)
    monkeypatch.setenv("ENVSTUDIO_CACHE_DIR", str(tmp_path / "cache-alone"))
    fresh = run_atlas(grid(methods=g.methods, envs=(env,), meshes=("knot",)), tmp_path / "alone")
    fresh = fresh.rows
    assert sessions.KEPT.made == made + 2 and len(pyramids) == 2
    for row in fresh:
        twin = next(r for r in shared if (r["mesh"], r["method"]) == ("knot", row["method"]))
        assert [twin[k] for k in (*NUMBERS, "gpu_bytes")] == [
            row[k] for k in (*NUMBERS, "gpu_bytes")
        ]


def test_the_page_loads_in_chromium_with_every_image_and_the_chart(tmp_path):
    """pem has no bake for this scene: listed as needing one, with no numbers."""
    result = run_atlas(grid(methods=("mirror", "kautz", "pem")), tmp_path)
    pem = next(r for r in result.rows if r["method"] == "pem")
    assert pem["skipped"].startswith("needs a bake") and result.failed == 0
    assert ">needs a bake<" in (tmp_path / "index.html").read_text()
    browser = shutil.which("chromium")
    assert browser, "chromium (Debian package) is needed to check the atlas page"
    page = subprocess.run(
        [
            browser,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--virtual-time-budget=5000",
            "--dump-dom",
            (tmp_path / "index.html").as_uri(),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    ).stdout
    check = page.split('id="page-check">')[1].split("<")[0]
    images, broken, points = (int(n) for n in re.findall(r"\d+", check))
    assert images >= 6 and broken == 0 and points == 2, check


def test_the_cluster_gives_the_pool_s_cells(tmp_path):
    g = grid(envs=("sunset", "night"))
    by_pool = run_atlas(g, tmp_path / "pool", jobs=2).rows
    by_dask = run_atlas(g, tmp_path / "dask", jobs=2, scheduler="local").rows
    key = lambda r: (r["env"], r["method"])  # noqa: E731
    for a, b in zip(sorted(by_pool, key=key), sorted(by_dask, key=key), strict=True):
        assert key(a) == key(b)
        np.testing.assert_allclose([a[k] for k in NUMBERS], [b[k] for k in NUMBERS], rtol=1e-6)


def test_the_pareto_front_keeps_the_points_nothing_beats():
    points = [(1.0, 0.10, "a"), (0.5, 0.20, "b"), (2.0, 0.05, "c"), (1.5, 0.15, "d")]
    assert [name for *_, name in pareto_front(points)] == ["b", "a", "c"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--methods", "nosuch"], "unknown method"),
        (["--envs", "nowhere"], "--envs nowhere"),
        (["--meshes", "blob"], "--meshes blob"),
        (["--exponents", "0"], "--exponents 0"),
        (["--jobs", "0"], "--jobs 0"),
    ],
)
def test_bad_input_is_one_line(tmp_path, capsys, args, message):
    assert main(["atlas", *args, "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_a_folder_of_another_grid_is_refused_unless_forced(tmp_path, capsys):
    (tmp_path / "atlas-settings.json").write_text(json.dumps({"size": [64, 64]}))
    assert atlas(tmp_path, "--methods", "mirror", "--exponents", "100") == 2
    assert "holds an atlas of other settings" in capsys.readouterr().err


def test_a_method_that_crashes_is_marked_and_the_rest_is_measured(tmp_path, monkeypatch):
    from envstudio.methods.kautz.method import KautzMethod

    def crash(self, frame):
        raise RuntimeError("boom\nmore")

    monkeypatch.setattr(KautzMethod, "render", crash)
    result = run_atlas(grid(), tmp_path)
    rows = {r["method"]: r for r in result.rows}
    assert rows["kautz"]["error"] == "RuntimeError: boom" and result.failed == 1
    assert rows["mirror"]["error"] is None and rows["mirror"]["scene_error"] > 0


def test_a_corrupt_cell_is_one_note_and_measured_again_with_its_images(tmp_path, capsys):
    tiny = ["--methods", "mirror", "--envs", "studio", "--meshes", "sphere", "--exponents", "10"]
    tiny += ["--size", "16x16", "--ssaa", "1", "--time-limit", "1", "--out", str(tmp_path)]
    assert main(["atlas", *tiny]) == 0
    cell = next((tmp_path / "cells").glob("*.json"))
    cell.write_text(cell.read_text()[:20])
    for png in cell.with_suffix("").glob("*.png"):
        png.unlink()
    capsys.readouterr()
    assert main(["atlas", *tiny]) == 0
    captured = capsys.readouterr()
    assert "(1 measured now)" in captured.out
    notes = [line for line in captured.err.splitlines() if "note:" in line]
    assert len(notes) == 1 and (cell.parent / f"{cell.name}.corrupt").is_file()
    row = json.loads((tmp_path / "atlas.json").read_text())["cells"][0]
    assert row["error"] is None and (tmp_path / "cells" / row["image"]).is_file()
