"""The orbits' cache (methods/pem/bake/orbit.py): least recently used orbits go first over
the cap; a damaged entry is one note, discarded and baked again."""

from __future__ import annotations

import os
import shutil
import time

import pytest

from envstudio.errors import InputFileError
from envstudio.methods.pem.bake.orbit import OrbitStore, orbit_cache_cap, prune_orbits


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


# -- damaged entries heal (issue 38 item 11) ---------------------------------------------------

#: A tiny orbit (20° apart, 16² bake, 8² maps, CPU lookups): a view bakes in about 0.5 s.
TINY = {"size": 16, "samples": 1, "em_size": 8, "rtol": 1e-3}
VIEW = 108  # the scene camera's view


def _store(root):
    return OrbitStore("room", None, (20.0, 20.0), root=root, parameters=dict(TINY))


@pytest.fixture(scope="module")
def baked(tmp_path_factory):
    """An orbit folder with the shell and one baked view."""
    root = tmp_path_factory.mktemp("orbit")
    store = _store(root)
    store.shell()
    store.bake([VIEW], workers=0)
    return root


def _flip(path):
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x40
    path.write_bytes(bytes(data))


def _folder(path):
    path.unlink()
    (path / "inside").mkdir(parents=True)


DAMAGE = {
    "truncated": lambda p: p.write_bytes(p.read_bytes()[: p.stat().st_size // 2]),
    "bit-flipped": _flip,
    "empty": lambda p: p.write_bytes(b""),
    "folder": _folder,
}


def _played(store, view=VIEW):
    """What headless playback does: the shell, then the view, baked where it does not load."""
    store.shell()
    if store.load(view) is None:
        store.bake([view], workers=0)
    return store.load(view)


def _assert_one_note_then_healed(root, path, capsys, view=VIEW):
    err = capsys.readouterr().err.strip().splitlines()
    assert path.is_file()
    assert len(err) == 1 and err[0].startswith(f"envstudio: note: {path}"), err
    assert err[0].endswith("discarded, baking again")
    assert _played(_store(root), view) is not None  # healed: the next run is silent
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("entry", ["views/view-00108.pem", "shell.npz"])
@pytest.mark.parametrize("kind", DAMAGE)
def test_a_damaged_entry_is_one_note_and_baked_again(baked, tmp_path, capsys, entry, kind):
    root = tmp_path / "cache"
    shutil.copytree(baked, root)
    store = _store(root)
    path = store.folder / entry
    DAMAGE[kind](path)
    assert _played(store) is not None
    _assert_one_note_then_healed(root, path, capsys)


def test_another_views_file_in_a_views_place_is_baked_again(baked, tmp_path, capsys):
    root = tmp_path / "cache"
    shutil.copytree(baked, root)
    store = _store(root)
    path = store.view_path(VIEW + 1)
    shutil.copy(store.view_path(VIEW), path)
    assert _played(store, VIEW + 1) is not None
    _assert_one_note_then_healed(root, path, capsys, VIEW + 1)


def _write_forever_ignoring_sigterm(path):
    """A writer stuck where SIGTERM cannot end it (as in an fsync): only SIGKILL does."""
    import signal
    import time

    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    path.write_bytes(b"half a view")
    while True:
        time.sleep(0.05)


def test_a_stopped_bake_ends_its_child_and_leaves_no_half_written_view(
    baked, tmp_path, monkeypatch
):
    import multiprocessing

    from envstudio.methods.pem import orbit_job
    from envstudio.methods.pem.orbit_job import OrbitBakeJob

    root = tmp_path / "cache"
    shutil.copytree(baked, root)
    store = _store(root)
    leftover = store.folder / "views" / ".view-00107.ab12cd34.pem"
    job = OrbitBakeJob(store, "room")
    monkeypatch.setattr(orbit_job, "JOIN_S", 0.2)
    child = multiprocessing.get_context("fork").Process(
        target=_write_forever_ignoring_sigterm, args=(leftover,), daemon=True
    )
    child.start()
    deadline = time.monotonic() + 30.0
    while not leftover.exists():
        assert time.monotonic() < deadline, "the child wrote nothing in 30 s"
        time.sleep(0.01)
    job._process, pid = child, child.pid
    job.stop()
    with pytest.raises(ProcessLookupError):  # killed after JOIN_S and reaped, not left running
        os.kill(pid, 0)
    assert not job.running
    names = sorted(p.name for p in (store.folder / "views").iterdir())
    assert names == [store.view_path(VIEW).name] and store.done() == {VIEW}
