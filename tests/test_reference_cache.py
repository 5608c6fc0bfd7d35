"""The saved-reference cache stays within its size limit, least recently used first."""

from __future__ import annotations

import os

import numpy as np
import pytest

from envstudio.errors import ParameterError
from envstudio.render.reference_cache import cache_limit_bytes, load_state, prune, save_state

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
