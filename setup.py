"""The wheel's one build step that pyproject.toml cannot say: package the top-level data.

The checkout keeps ``shaders/`` and ``assets/`` at the top level (DESIGN.md's layout); the
wheel carries them as package data ``envstudio/shaders`` and ``envstudio/assets``, found at
run time through ``importlib.resources`` (``envstudio.resources``). They are copied into the
build tree here, at build time, so the repository holds one copy. Everything under the two
folders is taken (``.glsl``, ``.exr``, ``.hdr``, ``.toml``, ``.pem``, ``.rsibr``, licences, ...)
but Python caches. An editable install (``pip install -e .``) copies nothing: the checkout's
folders are used where they are. The sdist carries them through ``MANIFEST.in``.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
PACKAGE = "envstudio"
DATA_FOLDERS = ("shaders", "assets")


class build_py_with_data(build_py):  # noqa: N801 (setuptools' command naming)
    """``build_py`` that also copies ``shaders/`` and ``assets/`` into ``envstudio/``."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        for name in DATA_FOLDERS:
            source = ROOT / name
            if not source.is_dir():
                raise SystemExit(f"setup.py: {source} is missing; build from a full checkout")
            target = Path(self.build_lib) / PACKAGE / name
            shutil.rmtree(target, ignore_errors=True)
            shutil.copytree(
                source, target, ignore=shutil.ignore_patterns("__pycache__", "*.py[co]")
            )


setup(cmdclass={"build_py": build_py_with_data})
