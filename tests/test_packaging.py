"""The wheel (issue 20): built, installed into a fresh venv outside the checkout, run elsewhere.

The wheel is built (``python -m build``: sdist, then the wheel from the sdist) from a copy of
the sources in a temporary folder, so the checkout gets no ``build/`` or ``*.egg-info``. The
fresh venv has no pip and no packages of its own; a ``.pth`` file puts the checkout venv's
site-packages behind its own, so the dependencies need no download. That folder's ``.pth``
files are not processed (only a site directory's are), so the checkout's editable install
(``__editable__.envmap_studio-*.pth`` → ``app/``) stays out, and the wheel's files are the
only ``envstudio`` there is: the test proves it from ``__file__`` and the data folders.
"""

from __future__ import annotations

import configparser
import os
import shutil
import subprocess
import sys
import sysconfig
import tarfile
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pytest

from envstudio.io.images import read_image

ROOT = Path(__file__).resolve().parents[1]
SOURCES = ("pyproject.toml", "setup.py", "MANIFEST.in", "README.md", "app", "shaders", "assets")
# The optional extras (dev: tests and packaging; cluster: Dask) and what only they bring.
OPTIONAL_MODULES = ("pytest", "ruff", "mitsuba", "drjit", "build", "PyInstaller", "dask")
TIMEOUT_S = 120
PIP_OPTIONS = ("--ignore-installed", "--disable-pip-version-check")


def _clean_env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV"))}
    return {**env, **extra}


def _run(argv: list[str], cwd: Path, **env: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        argv,
        cwd=cwd,
        env=_clean_env(**env),
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        check=False,
    )


def _checked(result: subprocess.CompletedProcess) -> str:
    assert result.returncode == 0, f"{result.args}:\n{result.stdout}\n{result.stderr}"
    assert "Traceback" not in result.stderr, result.stderr
    return result.stdout


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> tuple[Path, Path]:
    """(wheel, sdist) built from a copy of the checkout's sources."""
    tmp = tmp_path_factory.mktemp("wheel")
    source = tmp / "src"
    source.mkdir()
    ignore = shutil.ignore_patterns("__pycache__", "*.py[co]", "*.egg-info")
    for name in SOURCES:
        path = ROOT / name
        if path.is_dir():
            shutil.copytree(path, source / name, ignore=ignore)
        else:
            shutil.copy2(path, source / name)
    dist = tmp / "dist"
    # --no-isolation: the build backend (setuptools, pinned in requirements.lock) is the
    # checkout venv's, so the test needs no network
    _checked(
        _run(
            [sys.executable, "-m", "build", "--no-isolation", "--outdir", str(dist), "."],
            cwd=source,
        )
    )
    (wheel,) = dist.glob("envmap_studio-*.whl")
    (sdist,) = dist.glob("envmap_studio-*.tar.gz")
    return wheel, sdist


@pytest.fixture(scope="module")
def installed(built, tmp_path_factory) -> Path:
    """A fresh venv (outside the checkout) with the wheel installed; returns its bin/ folder."""
    wheel, _ = built
    venv = tmp_path_factory.mktemp("venv") / "venv"
    assert ROOT not in venv.parents
    _checked(_run([sys.executable, "-m", "venv", "--without-pip", str(venv)], cwd=venv.parent))
    python = venv / "bin" / "python"
    purelib = _run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
        cwd=venv.parent,
    )
    site = Path(_checked(purelib).strip())
    (site / "_checkout_dependencies.pth").write_text(sysconfig.get_path("purelib") + "\n")
    # pip comes from the checkout venv's site-packages too; --ignore-installed: the
    # checkout's own envmap-studio (visible there) is neither upgraded nor uninstalled
    _checked(
        _run(
            [
                str(python),
                "-m",
                "pip",
                "install",
                "-q",
                "--no-deps",
                "--no-index",
                *PIP_OPTIONS,
                str(wheel),
            ],
            cwd=venv.parent,
        )
    )
    return venv / "bin"


def test_wheel_carries_the_data_once(built):
    wheel, sdist = built
    names = set(zipfile.ZipFile(wheel).namelist())
    for folder in ("shaders", "assets"):
        expected = {
            f"envstudio/{folder}/{p.relative_to(ROOT / folder).as_posix()}"
            for p in (ROOT / folder).rglob("*")
            if p.is_file() and "__pycache__" not in p.parts
        }
        assert expected, folder
        assert expected <= names, sorted(expected - names)[:5]
    assert "envstudio/data/glossiness_fit.json" in names
    assert not any(n.startswith(("shaders/", "assets/", "app/")) for n in names)
    assert not (ROOT / "app" / "envstudio" / "shaders").exists()  # no second copy in the repo
    with tarfile.open(sdist) as archive:
        members = {Path(m).relative_to(Path(m).parts[0]).as_posix() for m in archive.getnames()}
    assert {"setup.py", "MANIFEST.in", "shaders/common", "assets/hdr/studio.exr"} <= members


def test_installed_wheel_runs_from_anywhere(installed, tmp_path):
    work = tmp_path / "elsewhere"
    work.mkdir()
    envstudio = str(installed / "envstudio")
    version = _checked(_run([envstudio, "--version"], cwd=work)).strip()
    from envstudio import __version__

    assert version == f"envstudio {__version__}"

    where = _checked(
        _run(
            [
                str(installed / "python"),
                "-c",
                "import envstudio, envstudio.resources as r; "
                "print(envstudio.__file__); print(r.shader_root()); print(r.asset_root())",
            ],
            cwd=work,
        )
    ).splitlines()
    venv = installed.parent
    for path in where:
        assert venv in Path(path).parents, (path, venv)
    assert Path(where[1]).name == "shaders" and Path(where[1]).parent.name == "envstudio"
    assert (Path(where[1]) / "common").is_dir()
    assert (Path(where[2]) / "hdr" / "studio.exr").is_file()

    methods = _checked(_run([envstudio, "methods"], cwd=work))
    for name in ("mirror", "kautz", "hwconv", "rsibr", "banks", "reference"):
        assert f"\n{name}:" in f"\n{methods}", methods

    out = work / "OUT.png"
    _checked(
        _run([envstudio, "render", "--method", "mirror", "--size", "32x32", "-o", "OUT.png"], work)
    )
    pixels = read_image(out)
    assert pixels.shape[:2] == (32, 32)
    assert (
        float(np.ptp(pixels)) > 0.1
        and len(np.unique(pixels.reshape(-1, pixels.shape[2]), axis=0)) > 16
    )


def test_installed_wheel_needs_no_optional_extra(installed, tmp_path):
    """``methods`` and ``render`` with every module of the dev and cluster extras unimportable."""
    blocker = (
        "import sys\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        f"        if name.split('.')[0] in {OPTIONAL_MODULES!r}:\n"
        "            raise ImportError(f'{name} blocked: an optional extra')\n"
        "sys.meta_path.insert(0, Block())\n"
        "from envstudio.cli import main\n"
        "assert main(['methods']) == 0\n"
        "sys.exit(main(['render', '--method', 'kautz', '--size', '24x24', '-o', 'k.png']))\n"
    )
    _checked(_run([str(installed / "python"), "-c", blocker], cwd=tmp_path))
    assert (tmp_path / "k.png").is_file()


def test_desktop_integration_files_agree():
    """The desktop entry, AppStream metadata, MIME types and icons of packaging/linux/."""
    linux = ROOT / "packaging" / "linux"
    app_id = "io.github.envmapstudio.EnvmapStudio"
    entry = configparser.ConfigParser(interpolation=None)
    entry.optionxform = str
    entry.read(linux / f"{app_id}.desktop")
    desktop = entry["Desktop Entry"]
    assert desktop["Exec"] == "envstudio view %f" and desktop["Icon"] == app_id
    entry_types = {t for t in desktop["MimeType"].split(";") if t}
    assert entry_types == {"image/x-exr", "image/vnd.radiance"}

    metainfo = ElementTree.parse(linux / f"{app_id}.metainfo.xml").getroot()
    assert metainfo.tag == "component" and metainfo.get("type") == "desktop-application"
    assert metainfo.findtext("id") == app_id
    assert metainfo.findtext("launchable") == f"{app_id}.desktop"
    assert {m.text for m in metainfo.iter("mediatype")} == entry_types
    from envstudio import __version__

    newest = metainfo.find("releases/release")
    assert newest.get("version") == __version__, "add the release to the metainfo's <releases>"

    namespace = "{http://www.freedesktop.org/standards/shared-mime-info}"
    mime = ElementTree.parse(linux / "envstudio-mime.xml").getroot()
    globs = {t.get("type"): {g.get("pattern") for g in t.iter(f"{namespace}glob")} for t in mime}
    assert set(globs) == entry_types and "*.exr" in globs["image/x-exr"]
    assert "*.hdr" in globs["image/vnd.radiance"]

    svg = ElementTree.parse(linux / "envstudio.svg").getroot()
    assert svg.tag == "{http://www.w3.org/2000/svg}svg" and svg.get("viewBox") == "0 0 256 256"
    for size in (16, 24, 32, 48, 64, 128, 256, 512):
        icon = read_image(linux / "icons" / f"{size}.png")
        assert icon.shape == (size, size, 4) and float(np.ptp(icon[..., :3])) > 0.3, size
