"""Shared fixtures. GL tests never skip: if no context can be made, they fail and say why."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from envstudio.gpu.context import create_headless_context
from envstudio.gpu.programs import ProgramLibrary, add_shader_folder

# the tests' probe shaders (``testing/<file>``), beside the tests and outside the wheel
add_shader_folder(Path(__file__).with_name("shaders") / "testing")


@pytest.fixture(autouse=True)
def _strict_numpy():
    with np.errstate(all="raise", under="ignore"):
        yield


@pytest.fixture(autouse=True)
def _private_cache(tmp_path, monkeypatch):
    """Saved reference accumulations go to the test's own folder, never the user's cache."""
    monkeypatch.setenv("ENVSTUDIO_CACHE_DIR", str(tmp_path / "cache"))


@pytest.fixture
def gl_ctx():
    """A fresh headless EGL context per test (llvmpipe on machines without a GPU)."""
    ctx = create_headless_context()
    yield ctx
    ctx.release()


@pytest.fixture
def programs(gl_ctx):
    """The program library of the test's context."""
    library = ProgramLibrary(gl_ctx)
    yield library
    library.release()
