"""Coupled inference (issue 31; not in seed 003): each view's maps drawn towards its neighbours'.

Weight 0 must be today's bake bit for bit: the independent per-view work unit,
the same parameters, the same file. A positive weight must pull neighbouring
views' maps together.
"""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.io.scene_file import load_scene, resolve_scene
from envstudio.methods.pem.bake.bake import ViewTask, bake_view, neighbours
from envstudio.methods.pem.bake.lookups import PLAYBACK, REQUIRED
from envstudio.methods.pem.bake.views import arc_views, grid_views
from envstudio.methods.pem.commands import run_bake
from envstudio.methods.pem.lookups_gl import GlLookups
from test_bad_input import assert_one_line_error, run_cli

TINY = {"size": 32, "samples": 2, "em_size": 4, "workers": 0, "ptm": False}


def _arc(camera):
    return arc_views(camera, 3, 2.0)


def _spread(bake, model="distant"):
    """Mean |x_v − x_{v+1}| over every level of a model's maps."""
    return np.mean([np.abs(np.diff(level, axis=0)).mean() for level in bake.maps[model]])


def test_weight_zero_is_todays_bake_bit_for_bit(tmp_path):
    plain = run_bake("room", _arc, tmp_path / "plain.pem", **TINY)
    zero = run_bake("room", _arc, tmp_path / "zero.pem", coupling=0.0, coupling_passes=3, **TINY)
    assert (tmp_path / "zero.pem").read_bytes() == (tmp_path / "plain.pem").read_bytes()
    assert "coupling" not in zero.bake.parameters and set(zero.bake.maps) == set(REQUIRED)
    # and both are the independent work unit of before, view by view, every bit
    path = str(resolve_scene("room").resolve())
    for v, c in enumerate(_arc(load_scene("room").camera).cameras()):
        task = ViewTask(
            path, v, c.azimuth, c.elevation, c.distance, tuple(c.target), c.fov_y,
            32, 2, 4, 1e-3, 0, 1e-3, -2.0, "gl", GlLookups, REQUIRED,
        )  # fmt: skip
        alone = bake_view(task)
        for model in REQUIRED:
            for k, level in enumerate(zero.bake.maps[model]):
                assert np.array_equal(level[v], alone[f"{model}_{k}"])
        for name in PLAYBACK[:3]:
            assert zero.bake.playback_psnr[name][v] == alone[f"playback_{name}"]
    # a coupled bake pulls the views together, keeps its fit, and says it is coupled
    tied = run_bake("room", _arc, tmp_path / "tied.pem", coupling=1.0, coupling_passes=2, **TINY)
    assert tied.bake.parameters["coupling"] == 1.0
    assert len(tied.trace_seconds) == 9  # three passes of three views
    for model in REQUIRED:
        assert _spread(tied.bake, model) < 0.5 * _spread(plain.bake, model)
    assert np.nanmean(tied.bake.playback_psnr["layered"]) > 18.0


def test_neighbours_and_bad_weights(tmp_path, capsys):
    camera = load_scene("room").camera
    assert neighbours(arc_views(camera, 3, 2.0).describe()) == [[1], [0, 2], [1]]
    grid = neighbours(grid_views(camera, 3, 2.0, 2, 5.0).describe())
    assert grid[0] == [1, 3] and sorted(grid[4]) == [1, 3, 5]
    with pytest.raises(ValueError, match="coupling -1"):
        run_bake("room", _arc, tmp_path / "bad.pem", coupling=-1.0, **TINY)
    for option, words in (
        (["--coupling", "nan"], "--coupling nan: expected a weight in [0, 100]"),
        (["--coupling-passes", "0"], "--coupling-passes 0: expected at least 1"),
    ):
        argv = ["bake", "pem", "--scene", "room", "-o", str(tmp_path / "x.pem"), *option]
        assert_one_line_error(*run_cli(capsys, *argv), words)
    assert not (tmp_path / "x.pem").exists()
