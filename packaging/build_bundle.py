"""Build the standalone Linux bundle: ``dist/envstudio/``, a PyInstaller one-folder app.

Usage (from anywhere; paths default to the checkout's ``dist/`` and ``build/bundle/``)::

    .venv/bin/python packaging/build_bundle.py [--dist DIR] [--work DIR] [--cache DIR]

The folder starts on a Linux machine without Python (same or newer glibc than the build
machine): ``dist/envstudio/envstudio`` is the ``envstudio`` command. It carries the shaders and
assets as ``envstudio/shaders`` and ``envstudio/assets`` (found through importlib.resources, as
in the wheel), the native parts of moderngl/glcontext, glfw, imgui-bundle, OpenImageIO,
embreex, flip-evaluator (hooks in ``packaging/pyinstaller_hooks/``), and the distribution
metadata ``--version`` and ``doctor`` read. GL itself (libEGL, libGL, the Mesa or GPU
driver) is the machine's, never bundled, and so is the C++ runtime those drivers need
(libstdc++, libgcc_s): without GL the commands print one line (``doctor`` says more). The
optional extras (tests, Dask) are left out.

Beside the program: ``share/`` (the desktop entry, the icon as SVG and PNGs 16..512, the
AppStream metadata, the MIME types) and ``install-desktop.sh``, which installs them for the
user. The PNGs are rendered from ``packaging/linux/envstudio.svg`` with cairosvg when it
imports (``pip install cairosvg``; it needs the system's libcairo), else the committed PNGs
of ``packaging/linux/icons/`` (rendered the same way by ``packaging/linux/render_icons.py``)
are copied.

``--cache DIR`` keeps finished bundles keyed by a hash of every input (the sources, the
packaging files, ``requirements.lock`` and the versions of Python and PyInstaller): a rebuild
of unchanged sources copies the cached folder instead of running PyInstaller.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGING = ROOT / "packaging"
LINUX = PACKAGING / "linux"
NAME = "envstudio"
APP_ID = "io.github.envmapstudio.EnvmapStudio"
ICON_SIZES = (16, 24, 32, 48, 64, 128, 256, 512)
# Collected whole: small packages whose native parts or data are loaded by name at run time.
COLLECT_ALL = ("moderngl", "flip_evaluator", "embreex", "pyglm", "glm")
# The optional extras and what the bundle never uses (tests, notebooks, other GUI toolkits).
EXCLUDES = (
    "pytest",
    "_pytest",
    "ruff",
    "mitsuba",
    "drjit",
    "dask",
    "distributed",
    "PyInstaller",
    "build",
    "setuptools",
    "pip",
    "IPython",
    "tkinter",
    "PyQt5",
    "PyQt6",
    "PySide2",
    "PySide6",
    "pyglet",
    "imgui_bundle.demos_python",
    # the documentation's tooling (the `dev` extra): babel's messages pull in pkg_resources,
    # whose runtime hook needs setuptools' vendored packages, which the bundle leaves out
    "sphinx",
    "sphinx_gallery",
    "docutils",
    "babel",
    "numpydoc",
    "myst_parser",
    "myst_nb",
    "jupyter_cache",
    "sqlalchemy",
    "pkg_resources",
)
# The machine's own: GL drivers (Mesa's libEGL and LLVM, a GPU's libGL) load into the process and
# need the system's C++ runtime, which is at least as new as the build machine's; a bundled older
# copy would be found first and make them fail to load.
SYSTEM_LIBRARIES = ("libstdc++.so.6", "libgcc_s.so.1")
# freeze_support: the pem bake's process pool spawns its workers by running this program again
# (with multiprocessing's own arguments, which it handles and exits on), not a Python.
LAUNCHER = '''"""The bundle's entry point: the envstudio command."""

import multiprocessing
import sys

from envstudio.cli import main

if __name__ == "__main__":
    multiprocessing.freeze_support()
    sys.exit(main())
'''
INPUTS = ("app", "shaders", "assets", "packaging", "pyproject.toml", "requirements.lock")


def _sources_key() -> str:
    """Hash of every file the bundle is built from, and of the tools that build it."""
    digest = hashlib.sha256()
    import PyInstaller

    digest.update(f"{sys.version} {platform.machine()} {PyInstaller.__version__}\n".encode())
    for name in INPUTS:
        path = ROOT / name
        files = sorted(path.rglob("*")) if path.is_dir() else [path]
        for file in files:
            if file.is_file() and "__pycache__" not in file.parts:
                digest.update(file.relative_to(ROOT).as_posix().encode() + b"\0")
                digest.update(hashlib.sha256(file.read_bytes()).digest())
    return digest.hexdigest()[:16]


def _pyinstaller(dist: Path, work: Path) -> None:
    launcher = work / "launcher" / f"{NAME}_main.py"  # not envstudio.py: the package
    shutil.rmtree(launcher.parent, ignore_errors=True)  # PyInstaller searches the script's folder
    launcher.parent.mkdir(parents=True)
    launcher.write_text(LAUNCHER)
    sep = os.pathsep
    argv = [
        sys.executable,
        "-m",
        "PyInstaller",
        "--noconfirm",
        "--clean",
        "--log-level=WARN",
        "--onedir",
        "--console",
        f"--name={NAME}",
        f"--distpath={dist}",
        f"--workpath={work / 'pyinstaller'}",
        f"--specpath={work}",
        f"--paths={ROOT / 'app'}",
        f"--additional-hooks-dir={PACKAGING / 'pyinstaller_hooks'}",
        f"--add-data={ROOT / 'shaders'}{sep}envstudio/shaders",
        f"--add-data={ROOT / 'assets'}{sep}envstudio/assets",
        f"--add-data={ROOT / 'app' / 'envstudio' / 'data'}{sep}envstudio/data",
        "--collect-submodules=envstudio",
        # importlib.metadata: --version, doctor's package list (every dependency's version)
        "--recursive-copy-metadata=envmap-studio",
    ]
    argv += [f"--collect-all={name}" for name in COLLECT_ALL]
    argv += [f"--exclude-module={name}" for name in EXCLUDES]
    argv.append(str(launcher))
    # PYTHONPATH: this checkout's sources, ahead of whatever envstudio the venv has installed
    env = {**os.environ, "PYTHONPATH": str(ROOT / "app")}
    subprocess.run(argv, check=True, cwd=work, env=env)


def _icons(share: Path) -> str:
    """The icon as SVG and PNGs (hicolor layout) under ``share/icons``; says how they were made."""
    hicolor = share / "icons" / "hicolor"
    scalable = hicolor / "scalable" / "apps"
    scalable.mkdir(parents=True, exist_ok=True)
    shutil.copy2(LINUX / "envstudio.svg", scalable / f"{APP_ID}.svg")
    sys.path.insert(0, str(LINUX))
    try:
        from render_icons import render_pngs

        made = render_pngs(LINUX / "envstudio.svg", hicolor, APP_ID, ICON_SIZES)
    finally:
        sys.path.pop(0)
    if made:
        return "rendered from envstudio.svg with cairosvg"
    for size in ICON_SIZES:
        folder = hicolor / f"{size}x{size}" / "apps"
        folder.mkdir(parents=True, exist_ok=True)
        shutil.copy2(LINUX / "icons" / f"{size}.png", folder / f"{APP_ID}.png")
    return "copied from packaging/linux/icons (cairosvg unavailable)"


def _desktop_files(bundle: Path) -> str:
    share = bundle / "share"
    (share / "applications").mkdir(parents=True, exist_ok=True)
    shutil.copy2(LINUX / f"{APP_ID}.desktop", share / "applications" / f"{APP_ID}.desktop")
    (share / "metainfo").mkdir(parents=True, exist_ok=True)
    shutil.copy2(LINUX / f"{APP_ID}.metainfo.xml", share / "metainfo" / f"{APP_ID}.metainfo.xml")
    (share / "mime" / "packages").mkdir(parents=True, exist_ok=True)
    shutil.copy2(LINUX / "envstudio-mime.xml", share / "mime" / "packages" / f"{APP_ID}.xml")
    how = _icons(share)
    shutil.copy2(LINUX / "install-desktop.sh", bundle / "install-desktop.sh")
    (bundle / "install-desktop.sh").chmod(0o755)
    return how


def _size(folder: Path) -> int:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file() and not p.is_symlink())


def _save_to_cache(bundle: Path, cache: Path, key: str) -> None:
    """Keep ``bundle`` as ``cache/KEY/envstudio``, the only entry (a bundle is hundreds of MB)."""
    cache.mkdir(parents=True, exist_ok=True)
    partial = cache / f".{key}.{os.getpid()}.partial"
    shutil.rmtree(partial, ignore_errors=True)
    shutil.copytree(bundle, partial / NAME, symlinks=True)
    try:
        partial.rename(cache / key)
    except OSError:  # a concurrent build of the same sources saved it first
        shutil.rmtree(partial, ignore_errors=True)
    for entry in cache.iterdir():
        if entry.name != key and not entry.name.endswith(".partial"):
            shutil.rmtree(entry, ignore_errors=True)


def build(dist: Path, work: Path, cache: Path | None) -> Path:
    """Build (or copy from ``cache``) the bundle into ``dist/envstudio``; returns that folder."""
    missing = [tool for tool in ("ldd", "objdump", "objcopy") if shutil.which(tool) is None]
    if missing:
        raise SystemExit(
            f"build_bundle: PyInstaller needs {', '.join(missing)}: "
            "apt-get install --no-install-recommends binutils"
        )
    bundle = dist / NAME
    started = time.monotonic()
    key = _sources_key() if cache else None
    if cache is not None and (cache / key / NAME / NAME).is_file():
        shutil.rmtree(bundle, ignore_errors=True)
        shutil.copytree(cache / key / NAME, bundle, symlinks=True)
        print(f"build_bundle: {bundle} copied from the cache {cache / key}")
        return bundle
    work.mkdir(parents=True, exist_ok=True)
    _pyinstaller(dist, work)
    for name in SYSTEM_LIBRARIES:
        (bundle / "_internal" / name).unlink(missing_ok=True)
    icons = _desktop_files(bundle)
    seconds = time.monotonic() - started
    print(f"build_bundle: icons {icons}")
    print(
        f"build_bundle: {bundle} built in {seconds:.0f} s, "
        f"{_size(bundle) / 2**20:.0f} MB; run {bundle / NAME} --version"
    )
    if cache is not None:
        _save_to_cache(bundle, cache, key)
    return bundle


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dist", type=Path, default=ROOT / "dist", help="output folder")
    parser.add_argument("--work", type=Path, default=ROOT / "build" / "bundle", help="temp")
    parser.add_argument("--cache", type=Path, help="reuse bundles of identical sources")
    args = parser.parse_args(argv)
    if not sys.platform.startswith("linux"):
        parser.error("the bundle is built on Linux, for Linux")
    build(args.dist.resolve(), args.work.resolve(), args.cache.resolve() if args.cache else None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
