"""Viewer settings: round trip, corrupt files replaced by defaults with a warning, atomic writes."""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
from dataclasses import asdict
from pathlib import Path

import pytest

from envstudio.errors import OutputFileError
from envstudio.ui import settings as settings_module
from envstudio.ui.compare_panel import CompareState
from envstudio.ui.grid import FRACTIONS, GridState
from envstudio.ui.settings import ViewerSettings, load_settings, save_settings, settings_path


@pytest.fixture(autouse=True)
def config_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Every test gets its own settings folder."""
    folder = tmp_path / "config"
    monkeypatch.setenv("ENVSTUDIO_CONFIG_DIR", str(folder))
    return folder


def custom_settings() -> ViewerSettings:
    """Settings where every field differs from its default."""
    return ViewerSettings(
        method="kautz",
        method_values={"mirror": {"fresnel": 0.25, "kd": 0.5}, "kautz": {"lod_bias": 2.5}},
        display={"exposure": -1.5, "tonemap": "reinhard", "background": False},
        scene="room",
        environment="/data/maps/forest.exr",
        mesh="/data/meshes/teapot.obj",
        camera={"azimuth": 30.0, "elevation": -12.5, "distance": 4.0, "target": [0.1, 0.2, 0.3]},
        object_rotation=[10.0, -20.0, 30.0],
        turntable=True,
        turntable_speed=-45.0,
        window_size=[640, 480],
        imgui_ini="[Window][Method]\nPos=8,8\nSize=290,200\n",
        match_glossiness=False,
        grid={"on": True, "picked": ["mirror", "kautz"], "scale": 2},
        compare={"other": "hwconv", "split": False, "divider": 0.3, "heat": True},
        panels_shown=False,
    )


def test_round_trip(config_dir):
    original = custom_settings()
    assert asdict(original) != asdict(ViewerSettings()), "the fixture must change every field"
    for field, value in asdict(original).items():
        assert value != getattr(ViewerSettings(), field), field

    save_settings(original)
    loaded, warning = load_settings()

    assert warning is None
    assert loaded == original
    assert settings_path() == config_dir / "settings.json"
    assert sorted(p.name for p in config_dir.iterdir()) == ["settings.json"]


def test_the_grid_is_restored_as_it_was_left():
    """The methods picked, on, the tile fraction: saved, read back, applied (issue 29)."""
    methods = ["mirror", "rsibr", "kautz", "reference"]
    state = GridState()
    state.picked = ["mirror", "kautz"]
    state.scale.index = 3
    state.enter()
    save_settings(ViewerSettings(grid=state.as_settings(), match_glossiness=False))
    loaded, warning = load_settings()
    assert warning is None and loaded.match_glossiness is False

    restored = GridState()
    assert restored.restore(loaded.grid, methods) == []
    assert (restored.on, restored.picked, restored.scale.fraction) == (True, state.picked, 1 / 4)
    assert restored.names(methods) == ["mirror", "kautz"]

    fresh = GridState()  # a method since removed is dropped; bad entries are named, not fatal
    assert fresh.restore({"picked": ["gone", "rsibr"]}, methods) == []
    assert (fresh.on, fresh.picked, fresh.scale.index) == (False, ["rsibr"], 0)
    problems = fresh.restore({"on": "yes", "picked": 3, "scale": len(FRACTIONS)}, methods)
    assert [p.split(" = ")[0] for p in problems] == ["grid.picked", "grid.scale", "grid.on"]
    assert ViewerSettings().grid == {} and GridState().restore({}, methods) == []


def test_missing_file_gives_defaults_silently(config_dir):
    loaded, warning = load_settings()
    assert (loaded, warning) == (ViewerSettings(), None)
    assert not settings_path().exists()


def test_unknown_keys_are_ignored(config_dir):
    config_dir.mkdir(parents=True, exist_ok=True)
    settings_path().write_text(json.dumps({"method": "mirror", "from_a_later_version": 1}))
    loaded, warning = load_settings()
    assert warning is None
    assert loaded == ViewerSettings(method="mirror")


@pytest.mark.parametrize(
    "content",
    [
        b"{not json",
        b"",
        b"\xff\xfe\x00garbage",
        b"[1, 2, 3]",
        b'{"method": 3}',
        b'{"window_size": "large"}',
        b'{"camera": [1, 2, 3]}',
        b'{"turntable_speed": true}',
        b'{"scene": 7}',
    ],
    ids=[
        "syntax",
        "empty",
        "binary",
        "not-an-object",
        "method-number",
        "size-string",
        "camera-list",
        "speed-bool",
        "scene-number",
    ],
)
def test_corrupt_file_gives_defaults_warning_and_backup(config_dir, content):
    config_dir.mkdir(parents=True, exist_ok=True)
    path = settings_path()
    path.write_bytes(content)

    loaded, warning = load_settings()

    assert loaded == ViewerSettings()
    assert warning is not None
    assert len(warning.splitlines()) == 1, warning
    assert str(path) in warning and "corrupt" in warning
    backup = path.with_name("settings.json.corrupt")
    assert backup.read_bytes() == content
    assert not path.exists(), "the corrupt file must be moved aside"

    # The next start is clean, and saving works again.
    assert load_settings() == (ViewerSettings(), None)
    save_settings(custom_settings())
    assert load_settings() == (custom_settings(), None)


def test_failure_before_writing_leaves_old_file(config_dir, monkeypatch):
    save_settings(custom_settings())
    before = settings_path().read_bytes()

    def broken_dumps(*args, **kwargs):
        raise RuntimeError("serialiser failed")

    monkeypatch.setattr(settings_module.json, "dumps", broken_dumps)
    with pytest.raises(RuntimeError, match="serialiser failed"):
        save_settings(ViewerSettings())

    assert settings_path().read_bytes() == before
    assert sorted(p.name for p in config_dir.iterdir()) == ["settings.json"]


def test_failure_while_writing_leaves_old_file_and_no_temporary(config_dir, monkeypatch):
    save_settings(custom_settings())
    before = settings_path().read_bytes()
    real_write_text = Path.write_text

    def write_half_then_fail(self, text, *args, **kwargs):
        real_write_text(self, text[: len(text) // 2], *args, **kwargs)
        raise OSError(28, "No space left on device")

    with monkeypatch.context() as patch:
        patch.setattr(Path, "write_text", write_half_then_fail)
        with pytest.raises(OutputFileError, match=r"settings\.json: not written, the disk is full"):
            save_settings(ViewerSettings())

    assert settings_path().read_bytes() == before
    assert sorted(p.name for p in config_dir.iterdir()) == ["settings.json"]
    assert load_settings() == (custom_settings(), None)


def test_the_split_screen_is_restored_and_bad_entries_are_named():
    methods = ["mirror", "hwconv", "kautz"]
    state = CompareState(other="hwconv")
    state.settings.divider, state.settings.heat = 0.3, True
    restored = CompareState()
    assert restored.restore(state.as_settings(), methods) == []
    assert restored.as_settings() == state.as_settings()

    gone = CompareState()
    assert gone.restore({"other": "removed-plugin"}, methods) == []
    assert gone.other is None
    bad = CompareState()
    problems = bad.restore(
        {"other": 5, "split": "yes", "divider": 2.0, "heat_scale": None}, methods
    )
    assert [p.split(" = ")[0] for p in problems] == [
        "compare.other",
        "compare.split",
        "compare.divider",
        "compare.heat_scale",
    ]
    assert bad.as_settings() == CompareState().as_settings()


@contextlib.contextmanager
def read_only(folder: Path):
    """``folder`` read-only for the block: a read-only bind mount as root (the file system
    refuses, as a read-only one does), else a folder without its write bit."""
    if os.geteuid() != 0:
        folder.chmod(0o555)
        try:
            yield
        finally:
            folder.chmod(0o755)
        return
    mount = subprocess.run(["mount", "--bind", "-o", "ro", str(folder), str(folder)], check=False)
    if mount.returncode:  # root ignores a folder's write bit: only a mount can refuse it
        pytest.fail(f"cannot make {folder} read-only: `mount --bind -o ro` failed as root")
    try:
        yield
    finally:
        subprocess.run(["umount", str(folder)], check=True)


@pytest.mark.parametrize("where", ["corrupt file", "folder missing"])
def test_a_read_only_folder_gives_defaults_and_one_line_saying_nothing_is_saved(
    tmp_path, monkeypatch, where
):
    outer = tmp_path / "outer"
    outer.mkdir()
    folder = outer if where == "corrupt file" else outer / "envstudio"
    (outer / "settings.json").write_bytes(b"{not json")
    monkeypatch.setenv("ENVSTUDIO_CONFIG_DIR", str(folder))
    with read_only(outer):
        loaded, warning = load_settings()
        assert loaded == ViewerSettings()
        assert len(warning.splitlines()) == 1 and warning.endswith("settings will not be saved")
        with pytest.raises(OutputFileError) as error:  # the viewer prints it, one line
            save_settings(custom_settings())
        assert "\n" not in str(error.value)
    assert (outer / "settings.json").read_bytes() == b"{not json"  # nothing lost
    assert sorted(p.name for p in outer.iterdir()) == ["settings.json"]
