"""``envstudio --version`` and ``envstudio doctor`` (issue 20), in subprocesses (seconds)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def envstudio(*argv: str, **env: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "envstudio", *argv],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, **env},
        check=False,
    )


def test_version_is_pyprojects():
    # tomllib is 3.11+; the project supports 3.10
    pyproject = (ROOT / "pyproject.toml").read_text()
    expected = re.search(r'^version = "([^"]+)"', pyproject, re.MULTILINE).group(1)
    assert metadata.version("envmap-studio") == expected, "reinstall: pip install --no-deps -e ."
    result = envstudio("--version")
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == f"envstudio {expected}"


def test_doctor_reports_every_section(tmp_path):
    result = envstudio("doctor", ENVSTUDIO_CONFIG_DIR=str(tmp_path / "config"))
    out = result.stdout
    assert result.returncode == 0, out + result.stderr
    for heading in (
        "OpenGL (headless, EGL)",
        "Window (moderngl-window + glfw)",
        "Python",
        "Data and folders",
        "Missing",
    ):
        assert f"\n{heading}\n" in out, out
    assert "renderer" in out and "compute shaders" in out
    assert "reference" in out and "kautz" in out  # the methods that need OpenGL 4.3
    assert f"envmap-studio      {metadata.version('envmap-studio')}" in out
    assert f"numpy              {metadata.version('numpy')}" in out
    assert "nothing: everything envstudio uses is here" in out
    assert str(tmp_path / "config") in out and "not created yet" in out
    assert not (tmp_path / "config").exists()  # doctor looks, it does not create
    assert "Traceback" not in out + result.stderr


def test_doctor_names_a_hidden_egl_and_its_fix():
    # glcontext's own override (honoured by gpu/context.py through moderngl) points elsewhere
    result = envstudio("doctor", GLCONTEXT_LINUX_LIBEGL="/nonexistent/libEGL.so.1")
    out = result.stdout
    assert result.returncode == 1, out + result.stderr
    missing = out.split("\nMissing\n", 1)[1]
    assert "libEGL /nonexistent/libEGL.so.1" in missing
    assert "apt-get install --no-install-recommends libegl1 libegl-mesa0 libgl1-mesa-dri" in missing
    assert "unset GLCONTEXT_LINUX_LIBEGL" in missing
    assert "Traceback" not in out + result.stderr
