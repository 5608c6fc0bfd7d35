"""The orbits' cache cap (methods/pem/bake/orbit.py): least recently used orbits go first."""

from __future__ import annotations

import os

import pytest

from envstudio.errors import InputFileError
from envstudio.methods.pem.bake.orbit import orbit_cache_cap, prune_orbits


def _orbit(root, name, megabytes, used):
    folder = root / name
    (folder / "views").mkdir(parents=True)
    (folder / "views" / "view-00000.pem").write_bytes(b"\0" * int(megabytes * 1e6))
    for path in (folder / "views", folder):
        os.utime(path, (used, used))
    return folder


def test_least_recently_used_orbits_are_deleted_until_under_the_cap(tmp_path):
    old = _orbit(tmp_path, "orbit-room-a", 3, used=1000)
    recent = _orbit(tmp_path, "orbit-room-b", 3, used=3000)
    middle = _orbit(tmp_path, "orbit-room-c", 3, used=2000)
    current = _orbit(tmp_path, "orbit-room-d", 5, used=500)  # in use: never deleted
    other = tmp_path / "rsibr"  # not an orbit
    other.mkdir()
    # 14 MB in all, cap 9 MB: the oldest two others go, the current orbit stays
    assert prune_orbits(tmp_path, current, 9e6) == [old, middle]
    assert recent.exists() and current.exists() and other.exists()
    assert prune_orbits(tmp_path, current, 9e6) == []  # under the cap now
    assert prune_orbits(tmp_path, current, 1.0) == [recent]  # the current one alone may exceed
    assert current.exists()


def test_cache_cap_from_the_environment(monkeypatch):
    monkeypatch.setenv("ENVSTUDIO_ORBIT_CACHE_GB", "0.5")
    assert orbit_cache_cap() == 0.5e9
    monkeypatch.delenv("ENVSTUDIO_ORBIT_CACHE_GB")
    assert orbit_cache_cap() == 4e9
    for bad in ("-1", "lots", "nan"):
        monkeypatch.setenv("ENVSTUDIO_ORBIT_CACHE_GB", bad)
        with pytest.raises(InputFileError, match="expected a size in GB > 0"):
            orbit_cache_cap()
