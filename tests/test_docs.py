"""The documentation site (docs/, examples/gallery/) builds with warnings as errors, and its
pages show the pictures they reference: a broken cross-reference, a missing image or a gallery
example that fails, fails here. One build per module, into a temporary folder, from a copy of
docs/ (so the checkout's docs/_build and docs/gallery are left alone)."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import time
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from envstudio.engine.registry import available_methods

ROOT = Path(__file__).resolve().parents[1]
SPHINX = [sys.executable, "-m", "sphinx", "-b", "html", "-W", "--keep-going", "-q"]
PAGES = ("index.html", "getting-started.html", "viewer.html", "techniques/kautz.html")


def _copy_sources(target: Path) -> Path:
    generated = shutil.ignore_patterns("_build", "_generated", "gallery", "sg_execution_times.rst")
    shutil.copytree(ROOT / "docs", target, ignore=generated)
    return target


def _environment(tmp: Path, **extra: str) -> dict[str, str]:
    env = dict(os.environ, ENVSTUDIO_CHECKOUT=str(ROOT), ENVSTUDIO_CACHE_DIR=str(tmp / "cache"))
    env.update(extra)
    return env


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The built site (fresh caches: the gallery's bakes included in the time)."""
    tmp = tmp_path_factory.mktemp("docs")
    source, html = _copy_sources(tmp / "src"), tmp / "html"
    start = time.monotonic()
    result = subprocess.run(
        [*SPHINX, "-d", str(tmp / "doctrees"), str(source), str(html)],
        capture_output=True,
        text=True,
        timeout=600,
        env=_environment(tmp),
        check=False,
    )
    print(f"docs build: {time.monotonic() - start:.1f} s")
    assert result.returncode == 0, result.stdout + result.stderr
    return html


class _Images(HTMLParser):
    def __init__(self):
        super().__init__()
        self.sources: list[str] = []

    def handle_starttag(self, tag, attrs):
        if tag == "img":
            self.sources.append(dict(attrs).get("src") or "")


def _images(page: Path) -> list[str]:
    parser = _Images()
    parser.feed(page.read_text(encoding="utf-8"))
    return parser.sources


@pytest.mark.parametrize(("page", "least"), [(p, 1) for p in PAGES])
def test_the_pages_reference_images_that_exist(site, page, least):
    sources = _images(site / page)
    files = [s for s in sources if not s.startswith("data:")]
    assert len(files) >= least, sources
    for source in files:
        assert (site / page).parent.joinpath(source).is_file(), f"{page}: {source}"


def test_every_registered_method_has_its_page(site):
    for name, cls in available_methods().items():
        text = (site / "techniques" / f"{name}.html").read_text(encoding="utf-8")
        assert cls.describe()["paper"].split(" ")[0] in text
        for parameter in cls.parameters:  # the generated table, row for row
            cell = f'<span class="pre">{parameter.name}</span></code></p></td>'
            assert cell in text, (name, parameter.name)


def test_the_gallery_ran_every_example_and_shows_its_picture(site):
    examples = sorted(p.stem for p in (ROOT / "examples" / "gallery").glob("*.py"))
    assert len(examples) >= 4
    for name in examples:
        sources = _images(site / "gallery" / f"{name}.html")
        assert any(f"sphx_glr_{name}_001.png" in s for s in sources), (name, sources)


def test_the_viewer_tour_shows_the_window_at_every_step(site):
    """docs/viewer.md's pictures are the window's screenshots of this build: none blank (dark
    and light pixels both), the whole-window ones all of one size."""
    from PIL import Image

    sources = [s for s in _images(site / "viewer.html") if "_images/" in s]
    shots = {Path(s).stem.rstrip("0123456789"): s for s in sources}  # Sphinx numbers namesakes
    assert sorted(shots) == ["capture", "capture-file", "grid", "panels", "reference", "split"]
    windows = set()
    for name, source in shots.items():
        picture = np.asarray(Image.open(site / source).convert("RGB"), dtype=np.float64)
        assert picture.std() > 10.0, f"{source}: blank"
        assert picture.mean(axis=2).min() < 40 < picture.mean(axis=2).max(), source
        if name in {"panels", "split", "grid", "capture"}:
            windows.add(picture.shape[:2])
    assert len(windows) == 1, windows


def test_the_cli_reference_is_the_real_parser(site):
    text = (site / "reference" / "cli.html").read_text(encoding="utf-8")
    from envstudio.cli import build_parser

    commands = next(a for a in build_parser()._actions if a.choices and a.dest)
    for name in commands.choices:
        assert f"<h3>{name}<" in text, name


_CHECK = """<script>
window.__errors = [];
window.addEventListener("error", e => window.__errors.push(
  String(e.message || (e.target && (e.target.src || e.target.href)))), true);
const __error = console.error;
console.error = (...a) => { window.__errors.push(a.join(" ")); __error(...a); };
window.addEventListener("load", () => {
  const images = [...document.images];
  const broken = images.filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.src);
  const out = document.createElement("pre");
  out.id = "page-check";
  out.textContent = JSON.stringify({images: images.length, broken, errors: window.__errors});
  document.body.appendChild(out);
});
</script>"""


@pytest.mark.parametrize("page", PAGES)
def test_the_pages_load_in_chromium_with_every_image(site, page):
    browser = shutil.which("chromium")
    assert browser, "chromium (Debian package) is needed to check the documentation pages"
    original = site / page
    checked = original.with_name(original.stem + ".check.html")  # beside it: same relative paths
    checked.write_text(
        original.read_text(encoding="utf-8").replace("<head>", "<head>" + _CHECK, 1),
        encoding="utf-8",
    )
    dom = subprocess.run(
        [
            *(browser, "--headless", "--no-sandbox", "--disable-gpu"),
            *("--virtual-time-budget=5000", "--dump-dom", checked.as_uri()),
        ],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    ).stdout
    match = re.search(r'id="page-check">([^<]*)<', dom)
    assert match, dom[-2000:]
    report = json.loads(match.group(1).replace("&quot;", '"').replace("&amp;", "&"))
    assert report["images"] >= 1 and report["broken"] == [] and report["errors"] == [], report


def test_without_xvfb_the_build_stops_in_one_line(tmp_path):
    """No Xvfb on the PATH: one line naming it, before the gallery runs."""
    source = _copy_sources(tmp_path / "src")
    result = subprocess.run(
        [*SPHINX, str(source), str(tmp_path / "html")],
        capture_output=True,
        text=True,
        timeout=300,
        env=_environment(tmp_path, PATH=str(Path(sys.executable).parent)),
        check=False,
    )
    assert result.returncode == 2, result.stdout + result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Xvfb" in lines[0] and "Traceback" not in result.stderr, lines


def test_without_egl_the_build_stops_in_one_line(tmp_path):
    source = _copy_sources(tmp_path / "src")
    result = subprocess.run(
        [*SPHINX, str(source), str(tmp_path / "html")],
        capture_output=True,
        text=True,
        timeout=300,
        env=_environment(tmp_path, GLCONTEXT_LINUX_LIBEGL=str(tmp_path / "no-libEGL.so")),
        check=False,
    )
    assert result.returncode == 2, result.stdout + result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "EGL" in lines[0] and "Traceback" not in result.stderr, lines
