"""The public plugin API: the shipped methods' order, and a real distribution of
examples/plugin-flat installed with pip into a folder on sys.path (real entry points,
no monkeypatching), rendered headless, listed, drawn as a figure; a plugin that fails
to import or takes a name gives one line and leaves every other method working."""

from __future__ import annotations

import importlib.metadata
import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from envstudio.commands.methods import markdown_table
from envstudio.engine.registry import (
    ENTRY_POINT_GROUP,
    SHIPPED_DISTRIBUTION,
    available_methods,
    ground_truth_class,
)
from envstudio.io.images import read_image

ROOT = Path(__file__).resolve().parents[1]
COLOUR = (0.2, 0.6, 0.9)
AMBIENT = 0.25


def shipped_plugins() -> list:
    """The shipped distribution's plugins, read from its entry points (the one place a
    shipped method is declared), in their declared order."""
    points = importlib.metadata.distribution(SHIPPED_DISTRIBUTION).entry_points
    plugins = [p.load() for p in points if p.group == ENTRY_POINT_GROUP]
    return sorted(plugins, key=lambda plugin: plugin.order)


def test_shipped_methods_come_in_the_declared_order():
    """mirror, the seeds by their papers' publication (1999, 2000 §5.2, §5.3, 2001, 2004),
    today's engines' (2012, 2013), then the ground truth: each plugin's declared order."""
    plugins = shipped_plugins()
    assert [p.name for p in plugins][:2] == ["mirror", "rsibr"] and len(plugins) >= 9
    assert list(available_methods()) == [p.name for p in plugins]
    (truth,) = [p for p in plugins if p.ground_truth]
    assert ground_truth_class().name == truth.name == "reference" == plugins[-1].name


def test_the_readme_lists_the_registry():
    """The README's table of methods is ``envstudio methods --markdown``, row for row."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    block = readme.split("<!-- methods: envstudio methods --markdown -->\n")[1]
    block = block.split("\n<!-- end methods -->")[0]
    described = [cls.describe() for cls in available_methods().values()]
    assert block == markdown_table(described)


def _pip_install(source: Path, target: Path) -> None:
    result = subprocess.run(
        [
            *(sys.executable, "-m", "pip", "install", "--no-deps", "--no-index"),
            *("--no-build-isolation", "--disable-pip-version-check", "--quiet"),
            *("--target", str(target), str(source)),
        ],
        capture_output=True,
        text=True,
        timeout=180,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr


def _broken_plugins(folder: Path) -> Path:
    """A distribution with two bad entry points: one that fails to import, one that takes
    the shipped name ``mirror``."""
    package = folder / "envstudio_broken"
    package.mkdir(parents=True)
    (folder / "pyproject.toml").write_text(
        textwrap.dedent(
            """
            [build-system]
            requires = ["setuptools>=77"]
            build-backend = "setuptools.build_meta"
            [project]
            name = "envstudio-broken"
            version = "0.1.0"
            [project.entry-points."envstudio.methods"]
            broken = "envstudio_broken.missing:PLUGIN"
            impostor = "envstudio_broken:PLUGIN"
            [tool.setuptools]
            packages = ["envstudio_broken"]
            """
        )
    )
    (package / "__init__.py").write_text(
        "from envstudio.plugin import FrameInputs, Method, Plugin\n\n\n"
        "class Impostor(Method):\n"
        "    name = 'mirror'\n    title = 'Impostor'\n    summary = 'Takes a shipped name.'\n\n"
        "    def render(self, frame: FrameInputs) -> None:\n        pass\n\n\n"
        "PLUGIN = Plugin(Impostor)\n"
    )
    return folder


@pytest.fixture(scope="module")
def plugin_site(tmp_path_factory) -> Path:
    """examples/plugin-flat and the broken distribution, installed into one target folder."""
    target = tmp_path_factory.mktemp("site")
    example = tmp_path_factory.mktemp("example") / "plugin-flat"  # its build/ stays out of the tree
    shutil.copytree(ROOT / "examples" / "plugin-flat", example)
    _pip_install(example, target)
    _pip_install(_broken_plugins(tmp_path_factory.mktemp("broken")), target)
    return target


def _envstudio(site: Path, *argv: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]),
    }
    result = subprocess.run(
        [sys.executable, "-m", "envstudio", *argv],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "Traceback" not in result.stderr, result.stderr
    return result


def test_an_installed_plugin_is_listed_after_the_shipped_methods_and_bad_ones_are_one_line(
    plugin_site, tmp_path
):
    result = _envstudio(plugin_site, "methods", "--json", cwd=tmp_path)
    methods = json.loads(result.stdout)["methods"]
    assert [m["name"] for m in methods] == [*available_methods(), "flat"]
    flat = methods[-1]
    assert flat["parameters"][0] == {
        "name": "colour",
        "kind": "color",
        "default": [0.8, 0.3, 0.1],
        "minimum": 0.0,
        "maximum": 1.0,
        "help": "Linear RGB of the surface.",
        "log": False,
        "rebuild": False,
    }
    assert methods[0]["title"] == "Mirror (Blinn–Newell)"  # the shipped mirror, not the impostor
    warnings = [line for line in result.stderr.splitlines() if line.startswith("envstudio: warn")]
    assert len(warnings) == 2, result.stderr
    broken = next(line for line in warnings if "plugin broken " in line)
    assert "envstudio_broken.missing:PLUGIN" in broken and "ModuleNotFoundError" in broken
    impostor = next(line for line in warnings if "plugin impostor " in line)
    assert "method name 'mirror' is already taken; left out" in impostor


def test_the_plugin_renders_headless_with_its_own_shader_and_include(plugin_site, tmp_path):
    """EXR output, linear: every reflector pixel is COLOUR times one factor in [ambient, 1]
    (flat/shade.glsl's key light), and both ends of the range show on the object."""
    out = tmp_path / "flat.exr"
    colour = ",".join(map(str, COLOUR))
    _envstudio(
        plugin_site,
        *("render", "--method", "flat", "--size", "64x64", "-o", str(out)),
        *("--param", f"colour={colour}", "--param", "background=false"),
        cwd=tmp_path,
    )
    image = read_image(out)[..., :3].astype(np.float64)
    covered = image.sum(axis=-1) > 0
    assert 0.1 < covered.mean() < 0.9
    factor = image[covered] / np.asarray(COLOUR)
    np.testing.assert_allclose(factor, factor[:, :1].repeat(3, axis=1), rtol=2e-3, atol=1e-4)
    assert factor.min() >= AMBIENT - 1e-3 and factor.max() <= 1.0 + 1e-3
    assert factor.min() < AMBIENT + 0.02 and factor.max() > 0.95


def test_the_plugin_figure_is_drawn_by_envstudio_figure(plugin_site, tmp_path):
    out = tmp_path / "swatches.png"
    result = _envstudio(
        plugin_site,
        *("figure", "flat-swatches", "--size", "32x32", "-o", str(out)),
        *("--param", "background=false"),
        cwd=tmp_path,
    )
    assert "red, green and blue" in result.stdout
    image = read_image(out)[..., :3].astype(np.float64)
    assert image.shape[:2] == (32, 3 * 32 + 2 * 2)
    for panel, channel in enumerate((0, 1, 2)):
        pixels = image[:, panel * 34 : panel * 34 + 32].reshape(-1, 3)
        lit = pixels[pixels.sum(axis=1) > pixels.sum(axis=1).max() * 0.5]
        assert (lit.argmax(axis=1) == channel).mean() > 0.9
