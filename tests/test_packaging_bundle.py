"""The standalone Linux bundle (issue 20): built by packaging/build_bundle.py, then run.

The bundle is built once per session (about 40 s of PyInstaller on two cores; a copy from
``build/bundle-cache/`` when the sources are unchanged since the last build there, which a
clean clone does not have) and run as a user would: from another folder, with no Python
variables and no virtual environment on PATH. It renders headless, opens the viewer on an
environment under its own Xvfb, answers a machine without GL with doctor's one line, and its
install-desktop.sh installs the desktop integration for a user (and removes it again).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from envstudio.io.images import read_image
from test_packaging import _checked
from test_window_smoke import xvfb  # noqa: F401 (the fixture: a private Xvfb server)

ROOT = Path(__file__).resolve().parents[1]
APP_ID = "io.github.envmapstudio.EnvmapStudio"
ICON_SIZES = (16, 24, 32, 48, 64, 128, 256, 512)
NO_GL = {
    "GLCONTEXT_LINUX_LIBEGL": "/nonexistent/libEGL.so.1",
    "GLCONTEXT_LINUX_LIBGL": "/nonexistent/libGL.so.1",
}
TIMEOUT_S = 120
# unchanged sources since the last build here: a copy instead of a build (/build/ is ignored)
BUNDLE_CACHE = ROOT / "build" / "bundle-cache"


def _user_env(tmp: Path, **extra: str) -> dict[str, str]:
    """A user's environment: no Python variables, no venv on PATH, private config and cache."""
    env = {
        k: v
        for k, v in os.environ.items()
        if not k.startswith(("PYTHON", "VIRTUAL_ENV", "GLCONTEXT_", "DISPLAY", "WAYLAND"))
    }
    env["PATH"] = "/usr/local/bin:/usr/bin:/bin"
    env["ENVSTUDIO_CONFIG_DIR"] = str(tmp / "config")
    env["ENVSTUDIO_CACHE_DIR"] = str(tmp / "cache")
    return {**env, **extra}


def _run(argv: list[str], cwd: Path, **env: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        argv,
        cwd=cwd,
        env=_user_env(cwd, **env),
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        check=False,
    )


@pytest.fixture(scope="module")
def bundle(tmp_path_factory) -> Iterator[Path]:
    """The built bundle folder (``dist/envstudio`` of packaging/build_bundle.py)."""
    tmp = tmp_path_factory.mktemp("bundle")
    options = ["--dist", tmp / "dist", "--work", tmp / "work", "--cache", BUNDLE_CACHE]
    build = subprocess.run(
        [sys.executable, ROOT / "packaging" / "build_bundle.py", *map(str, options)],
        capture_output=True,
        text=True,
        timeout=900,
        check=False,
    )
    assert build.returncode == 0, build.stdout + build.stderr
    folder = tmp / "dist" / "envstudio"
    assert (folder / "envstudio").is_file(), build.stdout
    yield folder
    shutil.rmtree(tmp, ignore_errors=True)  # hundreds of MB; pytest keeps three runs' folders


def test_bundle_runs_headless_without_python(bundle, tmp_path):
    program = str(bundle / "envstudio")
    for system in ("libstdc++.so.6", "libgcc_s.so.1", "libEGL.so.1", "libGL.so.1"):
        assert not (bundle / "_internal" / system).exists(), f"{system}: the machine's, not ours"
    from envstudio import __version__

    assert _checked(_run([program, "--version"], tmp_path)).strip() == f"envstudio {__version__}"
    methods = _checked(_run([program, "methods"], tmp_path))
    for name in ("mirror", "kautz", "hwconv", "rsibr", "banks", "reference"):
        assert f"\n{name}:" in f"\n{methods}", methods
    _checked(
        _run([program, "render", "--method", "mirror", "--size", "32x32", "-o", "a.png"], tmp_path)
    )
    pixels = read_image(tmp_path / "a.png")
    assert pixels.shape[:2] == (32, 32)
    assert float(np.ptp(pixels)) > 0.1

    doctor = _run([program, "doctor"], tmp_path)
    assert doctor.returncode == 0, doctor.stdout + doctor.stderr
    internal = bundle / "_internal" / "envstudio"
    assert f"shaders            {internal / 'shaders'}" in doctor.stdout, doctor.stdout
    assert f"assets             {internal / 'assets'}" in doctor.stdout, doctor.stdout


def test_bundle_bakes_on_a_process_pool(bundle, tmp_path):
    """The pem bake's spawned workers are the bundle itself run again (freeze_support)."""
    bake = ["bake", "pem", "--scene", "room", "--views", "2", "--size", "16", "--samples", "1"]
    options = ["--em-size", "8", "--workers", "2", "-o", "room.pem"]
    _checked(_run([str(bundle / "envstudio"), *bake, *options], tmp_path))
    assert (tmp_path / "room.pem").is_file()


def test_bundle_viewer_opens_a_file_under_xvfb(bundle, xvfb, tmp_path):  # noqa: F811
    environment = tmp_path / "city.exr"
    environment.write_bytes((ROOT / "assets" / "hdr" / "city.exr").read_bytes())
    shot = tmp_path / "shot.png"
    view = ["view", str(environment), "--frames", "3", "--screenshot", str(shot)]
    result = _run(
        [str(bundle / "envstudio"), *view],
        tmp_path,
        DISPLAY=xvfb,
    )
    _checked(result)
    image = read_image(shot)
    assert image.shape[0] > 100 and float(image.std()) > 0.05
    settings = json.loads((tmp_path / "config" / "settings.json").read_text())
    assert settings["environment"] == str(environment), settings  # it was the one shown


def test_bundle_without_gl_says_what_is_missing_in_one_line(bundle, tmp_path):
    program = str(bundle / "envstudio")
    render = _run([program, "render", "--size", "8x8", "-o", "a.png"], tmp_path, **NO_GL)
    assert render.returncode == 2, render.stderr
    lines = render.stderr.strip().splitlines()
    assert len(lines) == 1, render.stderr
    assert lines[0].startswith("envstudio: error: no OpenGL 3.3 context through EGL"), lines
    assert "libegl-mesa0" in lines[0] and "envstudio doctor" in lines[0]

    view = _run([program, "view", "--frames", "1"], tmp_path, **NO_GL)
    assert view.returncode == 2, view.stderr
    assert len(view.stderr.strip().splitlines()) == 1, view.stderr
    assert view.stderr.startswith("envstudio: error: no display"), view.stderr

    doctor = _run([program, "doctor"], tmp_path, **NO_GL)
    assert doctor.returncode == 1, doctor.stdout
    assert "Traceback" not in doctor.stdout + doctor.stderr
    missing = doctor.stdout.split("\nMissing\n")[1]
    assert (
        "libEGL /nonexistent/libEGL.so.1" in missing and "unset GLCONTEXT_LINUX_LIBEGL" in missing
    )


def test_bundle_installs_its_desktop_integration(bundle, tmp_path):
    data, bin_dir = tmp_path / "share", tmp_path / "bin"
    env = {"HOME": str(tmp_path), "XDG_DATA_HOME": str(data), "ENVSTUDIO_BIN_DIR": str(bin_dir)}
    _checked(_run([str(bundle / "install-desktop.sh")], tmp_path, **env))
    entry = (data / "applications" / f"{APP_ID}.desktop").read_text()
    assert f'Exec="{bundle / "envstudio"}" view %f' in entry.splitlines(), entry
    assert "MimeType=image/x-exr;image/vnd.radiance;" in entry.splitlines()
    icons = data / "icons" / "hicolor"
    assert (icons / "scalable" / "apps" / f"{APP_ID}.svg").is_file()
    for size in ICON_SIZES:
        icon = read_image(icons / f"{size}x{size}" / "apps" / f"{APP_ID}.png")
        assert icon.shape[:2] == (size, size)
    assert (data / "metainfo" / f"{APP_ID}.metainfo.xml").is_file()
    assert (data / "mime" / "packages" / f"{APP_ID}.xml").is_file()
    assert (bin_dir / "envstudio").resolve() == (bundle / "envstudio").resolve()

    _checked(_run([str(bundle / "install-desktop.sh"), "--uninstall"], tmp_path, **env))
    assert not (data / "applications" / f"{APP_ID}.desktop").exists()
    assert not list(icons.rglob(f"{APP_ID}.*"))
    assert not (bin_dir / "envstudio").exists()
