"""One cache folder for every cached result: the override and the user cache, and its users."""

from __future__ import annotations

from pathlib import Path

from envstudio.io.cache_folder import cache_folder
from envstudio.measure.ground_truth_cache import cache_dir as ground_truth_dir
from envstudio.methods.pem.bake.orbit import orbit_cache_dir
from envstudio.methods.rsibr.bake.bake import cache_dir as rsibr_dir
from envstudio.methods.splitsum.dfg import cache_dir as splitsum_dir


def test_every_cache_lies_in_the_override(monkeypatch, tmp_path):
    monkeypatch.setenv("ENVSTUDIO_CACHE_DIR", str(tmp_path))
    assert cache_folder() == ground_truth_dir() == tmp_path
    assert [orbit_cache_dir(), rsibr_dir(), splitsum_dir()] == [
        tmp_path / "pem",
        tmp_path / "rsibr",
        tmp_path / "splitsum",
    ]


def test_without_the_override_the_user_cache_holds_them(monkeypatch, tmp_path):
    monkeypatch.delenv("ENVSTUDIO_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert cache_folder() == Path(tmp_path) / "envstudio" == ground_truth_dir()
    assert orbit_cache_dir().parent == rsibr_dir().parent == cache_folder()
