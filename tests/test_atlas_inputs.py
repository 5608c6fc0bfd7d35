"""``envstudio atlas`` (issue 38): the grid checked whole before anything is written, every
corrupt entry of ``--out`` set aside and measured again, failed cells measured again, one
atlas at a time in a folder, strict JSON. No cell is measured here (test_atlas_gl.py does)."""

import argparse
import json
import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from envstudio.cli import main
from envstudio.commands import atlas as command
from envstudio.core.metrics import MIN_SIZE
from envstudio.errors import OutputFileError, UserError
from envstudio.io.images import write_image
from envstudio.measure.atlas.entries import write_json
from envstudio.measure.atlas.grid import AtlasGrid, SceneCell
from envstudio.measure.atlas.lock import folder_lock
from envstudio.measure.atlas.page import summary, write_outputs
from envstudio.measure.atlas.store import AtlasStore
from envstudio.measure.compare import MAX_SSAA

CELL = SceneCell("studio", "sphere", 10.0, 0.0, 0)
GRID = AtlasGrid(("mirror", "kautz"), ("studio",), ("sphere",), (10.0,), (0.0,), (16, 16), 1, 2, 1)
IMAGES = ("image", "heat_map", "reference_image")


def measured(method: str) -> dict:
    numbers = dict.fromkeys(
        ("approximation_error", "scene_error", "scene_only_error", "psnr_db", "flip"), 0.1
    )
    numbers |= {"approximation_psnr_db": None, "approximation_flip": None, "gpu_bytes": 64}
    images = {k: f"{CELL.key}/{method}.{k}.png" for k in IMAGES}
    row = {**CELL.__dict__, "method": method, "error": None, "reliable": True, **images}
    return row | numbers | {"reference_model": "phong", "ms_per_frame": 1.0, "cost_ratio": 1.0}


def stored(folder, rows) -> AtlasStore:
    """A folder as an atlas leaves it: settings, the scene's rows and their images."""
    AtlasStore(folder, GRID).add(CELL, rows)
    for row in rows:
        for key in IMAGES:
            if key in row:
                (folder / "cells" / row[key]).parent.mkdir(exist_ok=True)
                (folder / "cells" / row[key]).write_bytes(b"png")
    return AtlasStore(folder, GRID)


SPOILED = {
    "truncated": lambda p: p.write_text(p.read_text()[: len(p.read_text()) // 2]),
    "empty": lambda p: p.write_bytes(b""),
    "a list": lambda p: p.write_text("[1, 2]"),
    "foo rows": lambda p: p.write_text('[{"foo": 1}]'),
    "binary": lambda p: p.write_bytes(bytes(range(256))),
    "NaN": lambda p: p.write_text('[{"method": NaN}]'),
    "folder": lambda p: (p.unlink(), p.mkdir()),
}


@pytest.mark.parametrize("entry", ["atlas-settings.json", "cell"])
@pytest.mark.parametrize("spoil", list(SPOILED))
def test_a_corrupt_entry_is_set_aside_with_one_note_and_measured_again(tmp_path, entry, spoil):
    stored(tmp_path, [measured("mirror"), measured("kautz")])
    path = tmp_path / (f"cells/{CELL.key}.json" if entry == "cell" else entry)
    SPOILED[spoil](path)
    store = AtlasStore(tmp_path, GRID)
    assert store.missing(CELL, GRID.methods) == ["mirror", "kautz"]
    assert len(store.notes) == 1 and "set aside as" in store.notes[0], store.notes
    assert list(tmp_path.rglob("*.corrupt")), "the bad entry is kept, renamed"
    assert json.loads((tmp_path / "atlas-settings.json").read_text()) == GRID.settings


def test_cells_as_a_file_and_missing_images_are_measured_again(tmp_path):
    stored(tmp_path, [measured("mirror"), measured("kautz")])
    (tmp_path / "cells" / measured("kautz")["image"]).unlink()
    store = AtlasStore(tmp_path, GRID)
    assert store.missing(CELL, GRID.methods) == ["kautz"] and "missing" in store.notes[0]
    (tmp_path / "cells").rename(tmp_path / "old")
    (tmp_path / "cells").write_text("x")
    store = AtlasStore(tmp_path, GRID)
    assert store.missing(CELL, GRID.methods) == ["mirror", "kautz"] and len(store.notes) == 1


def test_a_failed_cell_keeps_its_reason_until_it_is_measured_again(tmp_path):
    failed = {**CELL.__dict__, "method": "kautz", "error": "RuntimeError: boom"}
    skipped = {**CELL.__dict__, "method": "pem", "error": None, "skipped": "needs a bake"}
    store = stored(tmp_path, [measured("mirror"), failed, skipped])
    assert store.missing(CELL, ("mirror", "kautz", "pem")) == ["kautz"] and not store.notes
    assert store.rows(CELL)[1]["error"] == "RuntimeError: boom"


def test_strict_json_refuses_nan_and_keeps_the_old_file(tmp_path):
    write_json(tmp_path / "a.json", {"x": 1.0})
    for bad in (math.nan, math.inf):
        with pytest.raises(ValueError):
            write_json(tmp_path / "a.json", {"x": bad})
    assert json.loads((tmp_path / "a.json").read_text()) == {"x": 1.0}


def test_one_atlas_at_a_time_in_a_folder(tmp_path):
    with folder_lock(tmp_path), pytest.raises(OutputFileError, match=f"process {os.getpid()}"):
        with folder_lock(tmp_path):
            pass
    with folder_lock(tmp_path):  # released
        pass


@pytest.fixture(scope="module")
def bad_envs(tmp_path_factory):
    root = tmp_path_factory.mktemp("envs")
    (root / "garbage.exr").write_bytes(b"not an image" * 10)
    nan = np.ones((8, 16, 3), np.float32)
    nan[1, 2] = np.nan
    eight_bit = write_image(root / "eight.png", np.full((8, 16, 3), 0.5, np.float32))
    return [
        str(root / "garbage.exr"),
        str(write_image(root / "nan.exr", nan)),
        str(eight_bit.rename(root / "eight.exr")),
        str(root / "nowhere.exr"),
    ]


BAD = [
    ["--envs", 0],  # an index into bad_envs
    ["--envs", 1],
    ["--envs", 2],
    ["--envs", 3],
    ["--exponents", "inf"],
    ["--exponents", "1e300"],
    ["--exponents", "1e-300"],
    ["--kd", "nan"],
    ["--time-limit", "inf"],
    ["--size", "1x1"],
    ["--ssaa", "0"],
    ["--ssaa=-1"],
    ["--ssaa", str(MAX_SSAA + 1)],
    ["--cameras", "0"],
    ["--out", ""],
]


@pytest.mark.parametrize("extra", BAD, ids=str)
def test_a_bad_grid_is_one_line_exit_2_and_nothing_written(
    tmp_path, monkeypatch, capsys, bad_envs, extra
):
    monkeypatch.chdir(tmp_path)
    extra = [bad_envs[a] if isinstance(a, int) else a for a in extra]
    out = [] if "--out" in extra else ["--out", "atlas"]
    args = ["atlas", "--methods", "mirror", "--envs", "studio", "--meshes", "sphere"]
    assert main([*args, *extra, *out]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())


def namespace(**options) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    command.add_arguments(parser)
    return parser.parse_args([f"--{k.replace('_', '-')}={v}" for k, v in options.items()])


NUMBER = st.one_of(
    st.sampled_from(["10", "0", "-1", "inf", "nan", "1e300", "1e-300", "1e6", "", "x"]),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)


@settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    exponents=st.lists(NUMBER, min_size=1, max_size=3).map(",".join),
    kd=st.lists(NUMBER, min_size=1, max_size=2).map(",".join),
    size=st.sampled_from(["16x16", "1x1", "10x64", "64", "0x0", "8193x16", "16x16x"]),
    cameras=st.sampled_from(["1", "3", "0", "-2", "1e3", "361", "x"]),
    time_limit=NUMBER,
    ssaa=st.sampled_from(["1", "2", "8", "9", "0", "-1", "2.5", "1000"]),
    envs=st.sampled_from(["studio", "studio,night", "nosuch", ",", "bad"]),
    meshes=st.sampled_from(["sphere", "sphere,knot", "blob", ""]),
    param=st.sampled_from(["max_samples=32", "max_samples=0", "nosuch=1", "kd=nan", "trace=x"]),
)
def test_any_grid_is_refused_in_one_line_or_every_cell_can_be_measured(
    tmp_path, bad_envs, **options
):
    options["envs"] = options["envs"].replace("bad", ",".join(bad_envs))
    before = set(tmp_path.iterdir())
    try:
        grid = command.grid_from_args(namespace(methods="mirror,kautz", **options, out="x"))
    except UserError as error:
        assert len(str(error).splitlines()) == 1 and str(error)
    else:
        assert all(math.isfinite(v) for v in (*grid.exponents, *grid.kds, grid.time_limit))
        assert 1 <= grid.ssaa <= MAX_SSAA and min(grid.size) >= MIN_SIZE and grid.cameras >= 1
        json.dumps(grid.to_json(), allow_nan=False)
    assert set(tmp_path.iterdir()) == before


def test_a_marked_cell_shows_its_mark_and_reason_and_the_summary_counts_it(tmp_path):
    """Every cell reliable or marked with the reason (issue 40): the matrix's † and hover,
    the summary's count, the csv's column."""
    reason = "the reference reached its time limit of 60 s before it converged"
    marked = {"reliable": False, "unreliable_reason": reason}
    rows = [measured("mirror"), measured("kautz") | marked]
    write_outputs(GRID, rows, tmp_path)
    page = (tmp_path / "index.html").read_text()
    assert page.count(" †</a>") == 1 and f"† scene error unreliable: {reason}" in page
    assert {s["method"]: s["marked"] for s in summary(rows)} == {"mirror": 0, "kautz": 1}
    assert reason in (tmp_path / "atlas.csv").read_text()


def test_the_default_grid_has_every_shipped_map_once_by_content():
    """A format copy is left out by default (and named on request); it is its original's
    radiance within RGBE's 8-bit mantissa at all but one pixel (a negative the EXR holds)."""
    from envstudio.io.images import read_image
    from envstudio.io.scene_file import shipped_environments
    from envstudio.measure.atlas.grid import FORMAT_COPIES

    shipped = shipped_environments()
    grid = command.grid_from_args(namespace(out="x"))
    assert set(grid.envs) == set(shipped) - set(FORMAT_COPIES) and len(grid.envs) == 8
    assert command.grid_from_args(namespace(envs="studio_rgbe.hdr", out="x")).envs == (
        "studio_rgbe.hdr",
    )
    for copy, original in FORMAT_COPIES.items():
        a, b = read_image(shipped[original]), read_image(shipped[copy])
        assert a.shape == b.shape
        off = np.abs(a - b).max(axis=-1) / np.maximum(a.max(axis=-1), 1e-30)
        assert np.count_nonzero(off > 2.0**-7) <= 1 and np.median(off) < 2.0**-8
        assert abs(b.mean() / a.mean() - 1.0) < 5e-3
