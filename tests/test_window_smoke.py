"""The real viewer (``python -m envstudio view``) in a subprocess under its own Xvfb server.

Never skipped: without Xvfb the tests fail and say so. The screenshot is
checked from its pixels: between the panels it equals a headless (EGL) render
of the same scene and method, where the reflector covers the view's centre;
the Method panel is ImGui's window colour blended over that render, with text.
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
from imgui_bundle import imgui

from envstudio.engine.registry import available_methods
from envstudio.engine.session import RenderSession
from envstudio.io.images import read_image
from envstudio.io.scene_setup import build_scene
from envstudio.ui.app import CYCLE_FRAMES
from envstudio.ui.panels import default_layout

WINDOW = (640, 480)
FIRST_METHOD = "mirror"
RUN_TIMEOUT_S = 60


@pytest.fixture(scope="module")
def xvfb() -> Iterator[str]:
    """A private Xvfb server; yields its DISPLAY (``:N``, the number Xvfb chose itself)."""
    program = shutil.which("Xvfb")
    if program is None:
        pytest.fail("Xvfb is not installed (Debian: apt install xvfb); the window tests need it")
    read_fd, write_fd = os.pipe()
    server = subprocess.Popen(
        [program, "-displayfd", str(write_fd), "-screen", "0", "1280x800x24", "-nolisten", "tcp"],
        pass_fds=(write_fd,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write_fd)
    try:
        with os.fdopen(read_fd) as pipe:
            number = pipe.readline().strip()
        if not number:
            pytest.fail(f"Xvfb exited with status {server.wait(5)} before reporting its display")
        yield f":{number}"
    finally:
        server.terminate()
        try:
            server.wait(5)
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait()


def run_view(config_dir: Path, display: str | None, *options: str) -> subprocess.CompletedProcess:
    """``python -m envstudio view *options`` with its own settings folder and ``display``."""
    env = dict(os.environ, ENVSTUDIO_CONFIG_DIR=str(config_dir))
    env.pop("WAYLAND_DISPLAY", None)
    env.pop("DISPLAY", None)
    if display:
        env["DISPLAY"] = display
    return subprocess.run(
        [sys.executable, "-m", "envstudio", "view", *options],
        env=env,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
    )


def envstudio_lines(stream: str) -> list[str]:
    """The lines the application printed (drivers may add their own noise)."""
    return [line for line in stream.splitlines() if line.startswith("envstudio:")]


def headless_frames(method: str) -> tuple[np.ndarray, np.ndarray]:
    """The default scene through EGL at the window size: (displayed uint8, reflector mask)."""
    session = RenderSession(build_scene())
    try:
        session.render_offscreen(method, WINDOW)
        displayed = session.read_ldr()
        session.renderer.display["background"] = False
        session.render_offscreen(method, WINDOW)
        mask = session.read_hdr().sum(axis=2) > 0.0
    finally:
        session.release()
    return displayed, mask


def imgui_window_colour() -> np.ndarray:
    """(4,) RGBA of ImGui's default (dark) window background."""
    context = imgui.create_context()
    try:
        colour = imgui.get_style_color_vec4(imgui.Col_.window_bg)
        return np.array([colour.x, colour.y, colour.z, colour.w])
    finally:
        imgui.destroy_context(context)


def test_viewer_cycles_every_method_and_screenshot_shows_object_and_panel(xvfb, tmp_path):
    config = tmp_path / "config"
    config.mkdir()
    (config / "settings.json").write_text(json.dumps({"window_size": list(WINDOW)}))
    methods = list(available_methods())
    # The cycle starts at FIRST_METHOD and is back there on the last frame.
    frames = CYCLE_FRAMES * len(methods) + 1
    shot = tmp_path / "shot.png"

    result = run_view(
        config,
        xvfb,
        "--method",
        FIRST_METHOD,
        "--frames",
        str(frames),
        "--cycle-methods",
        "--screenshot",
        str(shot),
    )

    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    assert envstudio_lines(result.stderr) == [], "a method reported an error"
    shown = [line.removeprefix("envstudio: method ") for line in envstudio_lines(result.stdout)]
    assert set(shown) == set(methods), result.stdout
    assert shown[0] == FIRST_METHOD
    saved = json.loads((config / "settings.json").read_text())
    assert saved["method"] == FIRST_METHOD and saved["window_size"] == list(WINDOW)

    image = np.round(read_image(shot) * 255.0).astype(np.int16)
    assert image.shape == (WINDOW[1], WINDOW[0], 3)
    expected, reflector = headless_frames(FIRST_METHOD)
    expected = expected.astype(np.int16)
    layout = default_layout(WINDOW)

    # The object: the gap between the panel columns, around the centre, is the
    # scene as rendered headless; the reflector fills much of it, non-uniformly.
    left = int(layout["Method"][0] + layout["Method"][2]) + 2
    right = int(layout["Stats"][0]) - 2
    rows = slice(WINDOW[1] // 2 - 100, WINDOW[1] // 2 + 100)
    gap = image[rows, left:right]
    assert np.abs(gap - expected[rows, left:right]).max() <= 3
    assert reflector[rows, left:right].mean() > 0.3, "the reflector is not in the view's centre"
    reflector_pixels = gap[reflector[rows, left:right]]
    assert reflector_pixels.std(axis=0).max() > 10.0, "the reflector is one flat colour"

    # The Method panel: body pixels are ImGui's window colour over the scene;
    # bright text strokes run along it.
    x, y, w, h = (int(v) for v in layout["Method"])
    body = (slice(y + 30, y + h - 4), slice(x + 4, x + w - 4))
    colour = imgui_window_colour()
    blended = colour[:3] * 255.0 * colour[3] + expected[body] * (1.0 - colour[3])
    panel_coloured = np.all(np.abs(image[body] - blended) <= 2.5, axis=2)
    assert panel_coloured.mean() > 0.4, panel_coloured.mean()
    text = image[body].min(axis=2) > 200
    assert 0.01 < text.mean() < 0.3, text.mean()
    columns = text.any(axis=0)
    assert np.count_nonzero(columns[1:] != columns[:-1]) > 20, "no separate glyphs in the panel"
    outside_panels = image[rows, left:right]
    assert not np.all(outside_panels.min(axis=2) > 200), "the centre is covered by text"


def test_corrupt_settings_warn_once_and_are_replaced(xvfb, tmp_path):
    config = tmp_path / "config"
    config.mkdir()
    corrupt = b'{"method": "mirror", "window_size": [640, 48'
    (config / "settings.json").write_bytes(corrupt)

    result = run_view(config, xvfb, "--frames", "2")

    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    (warning,) = envstudio_lines(result.stderr)
    assert warning.startswith("envstudio: warning: ")
    assert "settings.json" in warning and "corrupt" in warning
    assert (config / "settings.json.corrupt").read_bytes() == corrupt
    saved = json.loads((config / "settings.json").read_text())
    assert saved["method"] in available_methods()


def test_no_display_exits_2_with_one_line(tmp_path):
    result = run_view(tmp_path / "config", None, "--frames", "1")

    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("envstudio: error: no display")


def test_with_the_panels_hidden_the_screenshot_is_the_headless_render(xvfb, tmp_path):
    """--hide-panels (Tab in the window): a clean view, pixel for pixel what `render` draws."""
    shot = tmp_path / "clean.png"
    result = run_view(
        tmp_path / "config",
        xvfb,
        *("--method", "hwconv", "--hide-panels", "--frames", "3", "--screenshot", str(shot)),
    )
    assert result.returncode == 0, result.stderr
    screen = read_image(shot)[..., :3]
    session = RenderSession(build_scene())
    try:
        session.render_offscreen("hwconv", (screen.shape[1], screen.shape[0]))
        displayed = session.read_ldr()
    finally:
        session.release()
    np.testing.assert_array_equal(np.round(screen * 255.0), displayed)
