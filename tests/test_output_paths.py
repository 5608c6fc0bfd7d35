"""Nothing lost on a bad output path or a full disk: every writing command, one line, exit 2,
no file left behind and an existing output unchanged. The read-only folder and the full disk
are real: tmpfs mounts where the test runs as root, a folder without write permission otherwise
(a full disk needs the mount)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from envstudio.resources import asset_root
from test_bad_input import assert_one_line_error, run_cli

STUDIO = str(asset_root() / "hdr" / "studio.exr")
IS_ROOT = os.geteuid() == 0

# Every command that writes a file, with the smallest work it can do; OUT is the output path.
WRITERS = {
    "render": ["render", "--method", "mirror", "--size", "32x32", "-o", "OUT.png"],
    "envmap": ["envmap", "--env", STUDIO, "--to", "cube", "--size", "8", "-o", "OUT.exr"],
    "prefilter": [
        *("prefilter", "--env", STUDIO, "--kernel", "phong", "--exponent", "10"),
        *("--algo", "hierarchical", "--param", "cube", "--size", "8", "-o", "OUT.exr"),
    ],
    "prefilter --chain": [
        *("prefilter", "--chain", "--param", "cube", "--env", STUDIO),
        *("--size", "8", "--levels", "2", "-o", "OUT.exr"),
    ],
    "bake rsibr": [
        *("bake", "rsibr", "--env", STUDIO, "--size", "8", "--samples", "4"),
        *("-o", "OUT.rsibr"),
    ],
    "figure": ["figure", "hwconv-distortion", "-o", "OUT.png"],
    "bench --json": [
        *("bench", "--methods", "mirror", "--size", "16x16", "--frames", "1"),
        *("--warmup", "0", "--json", "OUT.json"),
    ],
}


def _argv(name: str, out: Path) -> list[str]:
    suffix = Path(WRITERS[name][-1]).suffix
    return [a if not a.startswith("OUT.") else str(out.with_suffix(suffix)) for a in WRITERS[name]]


def _mount(folder: Path, options: str) -> None:
    folder.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(folder)], check=True)


@pytest.fixture
def read_only(tmp_path):
    """A read-only folder: a read-only tmpfs as root, else a folder without write permission."""
    folder = tmp_path / "read-only"
    if IS_ROOT:
        _mount(folder, "size=64k,ro")
        yield folder
        subprocess.run(["umount", str(folder)], check=True)
    else:
        folder.mkdir()
        folder.chmod(0o555)
        yield folder
        folder.chmod(0o755)


@pytest.fixture
def full_disk(tmp_path):
    """A 256 kB tmpfs holding a good ``keep`` file of each kind, then filled by dd."""
    if not IS_ROOT:
        pytest.skip("a full disk needs a tmpfs mount (root)")
    folder = tmp_path / "full"
    _mount(folder, "size=256k")
    for suffix in (".png", ".exr", ".rsibr", ".json"):
        (folder / f"keep{suffix}").write_bytes(b"the good file " + suffix.encode())
    subprocess.run(
        ["dd", "if=/dev/zero", f"of={folder / 'filler'}", "bs=4k", "count=100"],
        capture_output=True,
        check=False,  # dd ends with "No space left": that is the point
    )
    yield folder
    subprocess.run(["umount", str(folder)], check=True)


@pytest.mark.parametrize("name", list(WRITERS))
def test_an_output_that_is_a_folder_is_one_line(capsys, tmp_path, name):
    folder = tmp_path / f"out{Path(WRITERS[name][-1]).suffix}"  # a folder named as the file
    folder.mkdir()
    status, err = run_cli(capsys, *_argv(name, tmp_path / "out"))
    assert_one_line_error(status, err, str(folder), "is a folder")
    assert list(folder.iterdir()) == []


@pytest.mark.parametrize("name", list(WRITERS))
def test_a_read_only_folder_is_one_line_before_any_work(capsys, read_only, name):
    status, err = run_cli(capsys, *_argv(name, read_only / "out"))
    assert_one_line_error(status, err, str(read_only), "not writable")
    assert list(read_only.iterdir()) == []


@pytest.mark.parametrize("name", ["render", "prefilter", "envmap", "bake rsibr", "bench --json"])
def test_a_full_disk_keeps_the_old_file_and_says_so(capsys, full_disk, name):
    argv = _argv(name, full_disk / "keep")
    out = Path(next(a for a in argv if a.startswith(str(full_disk))))
    before = out.read_bytes()
    status, err = run_cli(capsys, *argv)
    assert_one_line_error(status, err, str(out), "disk is full", "unchanged")
    assert out.read_bytes() == before
    assert sorted(p.name for p in full_disk.iterdir() if p.name.startswith(".")) == []


def test_sigterm_ends_a_long_command_at_once_and_writes_nothing(tmp_path):
    """A killed brute-force prefilter stops within a second: exit 130, no file, no traceback."""
    out = tmp_path / "long.exr"
    argv = [*WRITERS["prefilter"][:-8], "--algo", "brute", "--param", "cube", "--size", "256"]
    process = subprocess.Popen(
        [sys.executable, "-m", "envstudio", *argv, "-o", str(out)],
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(3.0)  # past the imports, into the work
    assert process.poll() is None, process.stderr.read()
    start = time.perf_counter()
    process.send_signal(signal.SIGTERM)
    err = process.communicate(timeout=30)[1]
    assert time.perf_counter() - start < 5.0
    assert process.returncode == 130 and "interrupted" in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def test_bake_pem_on_a_full_disk_keeps_its_finished_views_and_says_how_to_resume(capsys, tmp_path):
    if not IS_ROOT:
        pytest.skip("a full disk needs a tmpfs mount (root)")
    folder = tmp_path / "small"
    _mount(folder, "size=40k")  # room for two views' parts of this tiny bake, not three
    try:
        out = folder / "room.pem"
        argv = ["bake", "pem", "--scene", "room", "--views", "3", "--size", "16", "--samples", "1"]
        argv += ["--em-size", "4", "--workers", "0", "--lookups", "cpu", "-o", str(out)]
        status, err = run_cli(capsys, *argv)
        assert_one_line_error(status, err, "disk is full", "views saved in", "resumes")
        parts = sorted(p.name for p in (folder / "room.pem.parts").iterdir())
        assert parts and len(parts) < 3 and not out.exists()
    finally:
        subprocess.run(["umount", str(folder)], check=True)
