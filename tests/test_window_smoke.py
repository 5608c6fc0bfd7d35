"""The real viewer (``python -m envstudio view``) in a subprocess under its own Xvfb server.

Never skipped: without Xvfb the tests fail and say so. Most runs go through
tests/window_probe.py, which runs the viewer unchanged and writes its last frame's
layout as JSON: the 3D view's rectangle (the dock space's central node), its GL
viewport, the render size and each panel's rectangle. The screenshot is checked
from its pixels: inside the view's rectangle it equals a headless (EGL) render
of the same scene and method at the view's size; the docked Method panel is
ImGui's window colour, with text.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from imgui_bundle import imgui

from envstudio.engine.grid_view import tile_layout
from envstudio.engine.registry import available_methods, ground_truth_class, method_class
from envstudio.engine.session import RenderSession
from envstudio.io.images import read_image
from envstudio.io.scene_setup import build_scene
from envstudio.measure.matching import GlossinessLink
from envstudio.ui.app import CYCLE_FRAMES
from envstudio.ui.docking import PANELS, ViewRect, gl_viewport

WINDOW = (640, 480)
FIRST_METHOD = "mirror"
RUN_TIMEOUT_S = 60
PROBE = Path(__file__).with_name("window_probe.py")


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


def run_view(
    config_dir: Path,
    display: str | None,
    *options: str,
    probe: Path | None = None,
    env: dict[str, str] | None = None,
) -> subprocess.CompletedProcess:
    """``python -m envstudio view *options`` with its own settings folder and ``display``;
    with ``probe``, through tests/window_probe.py, which writes the last frame's layout there;
    ``env`` adds environment variables."""
    env = dict(os.environ, **(env or {}), ENVSTUDIO_CONFIG_DIR=str(config_dir))
    env.pop("WAYLAND_DISPLAY", None)
    env.pop("DISPLAY", None)
    if display:
        env["DISPLAY"] = display
    if probe:
        command = [sys.executable, str(PROBE), str(probe)]
    else:
        command = [sys.executable, "-m", "envstudio"]
    return subprocess.run(
        [*command, "view", *options],
        env=env,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
    )


def envstudio_lines(stream: str) -> list[str]:
    """The lines the application printed (drivers may add their own noise)."""
    return [line for line in stream.splitlines() if line.startswith("envstudio:")]


def headless_frames(method: str, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """The default scene through EGL at ``size``: (displayed uint8, reflector mask)."""
    session = RenderSession(build_scene())
    try:
        session.render_offscreen(method, size)
        displayed = session.read_ldr()
        session.renderer.display["background"] = False
        session.render_offscreen(method, size)
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


def view_pixels(image: np.ndarray, record: dict) -> np.ndarray:
    """The 3D view's pixels of a screenshot (row 0 at the top), from the probe's viewport."""
    x, y, w, h = record["viewport"]
    top = image.shape[0] - (y + h)
    return image[top : top + h, x : x + w]


def rect_pixels(rect: list[float]) -> tuple[slice, slice]:
    """Rows and columns of a panel rectangle (points = pixels here), 4 pixels inside it."""
    x, y, w, h = (int(v) for v in rect)
    return slice(y + 4, y + h - 4), slice(x + 4, x + w - 4)


def test_viewer_cycles_every_method_and_screenshot_shows_object_and_panel(xvfb, tmp_path):
    config = tmp_path / "config"
    config.mkdir()
    (config / "settings.json").write_text(json.dumps({"window_size": list(WINDOW)}))
    methods = list(available_methods())
    # The cycle starts at FIRST_METHOD and is back there on the last frame.
    frames = CYCLE_FRAMES * len(methods) + 1
    shot = tmp_path / "shot.png"
    probe = tmp_path / "probe.json"

    result = run_view(
        config,
        xvfb,
        *("--method", FIRST_METHOD, "--frames", str(frames), "--cycle-methods"),
        *("--screenshot", str(shot)),
        probe=probe,
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
    record = json.loads(probe.read_text())
    expected, reflector = headless_frames(FIRST_METHOD, tuple(record["render_size"]))

    # The object: the 3D view is the scene as rendered headless at the view's size; the
    # reflector fills much of its centre, non-uniformly.
    view = view_pixels(image, record)
    np.testing.assert_array_equal(view, expected)
    h, w = reflector.shape
    centre = reflector[h // 4 : 3 * h // 4, w // 4 : 3 * w // 4]
    assert centre.mean() > 0.3, "the reflector is not in the view's centre"
    assert view[reflector].std(axis=0).max() > 10.0, "the reflector is one flat colour"

    # The Method panel, docked beside the view: its body is ImGui's window colour over the
    # cleared window; bright text strokes run along it.
    body = rect_pixels(record["panels"]["Method"]["rect"])
    colour = imgui_window_colour()
    panel_coloured = np.all(np.abs(image[body] - colour[:3] * 255.0 * colour[3]) <= 2.5, axis=2)
    assert panel_coloured.mean() > 0.4, panel_coloured.mean()
    text = image[body].min(axis=2) > 200
    assert 0.01 < text.mean() < 0.3, text.mean()
    strokes = np.count_nonzero(text[:, 1:] != text[:, :-1], axis=1)
    assert strokes.max() > 20, "no separate glyphs along a line of the panel"


def test_the_docked_panels_leave_the_3d_view_alone_and_the_layout_persists(xvfb, tmp_path):
    """Issue 28: the panels are docked around the view (the dock space's central node), which
    the scene fills at the central node's aspect ratio; the layout is saved and restored."""
    config = tmp_path / "config"  # no settings: the default window (1280x800) and layout
    shot = tmp_path / "shot.png"
    probe = tmp_path / "probe.json"
    options = ("--method", FIRST_METHOD, "--frames", "3")
    result = run_view(config, xvfb, *options, "--screenshot", str(shot), probe=probe)
    assert result.returncode == 0, result.stderr
    record = json.loads(probe.read_text())

    view = ViewRect(**record["view"])
    assert record["window_size"] == [1280, 800]
    assert view.width * view.height > 0.45 * 1280 * 800, "the view is less than half the window"
    panels = record["panels"]
    assert set(panels) == set(PANELS)
    for name, panel in panels.items():
        assert panel["docked"], f"{name} floats"
        assert not view.overlaps(ViewRect(*panel["rect"])), f"{name} covers the view"
    assert sum(panel["shown"] for panel in panels.values()) == len(PANELS) - 1, "one tab behind"
    # the GL viewport is the central node in framebuffer pixels, rendered at its size
    viewport = gl_viewport(view, record["window_size"], record["buffer_size"])
    assert record["viewport"] == list(viewport)
    assert record["render_size"] == list(viewport[2:])
    assert abs(viewport[2] / viewport[3] - view.aspect) < 1.0 / viewport[3]

    image = np.round(read_image(shot)[..., :3] * 255.0)
    expected, _ = headless_frames(FIRST_METHOD, tuple(record["render_size"]))
    np.testing.assert_array_equal(view_pixels(image, record), expected)

    saved = json.loads((config / "settings.json").read_text())["imgui_ini"]
    assert "[Docking][Data]" in saved and "CentralNode=1" in saved
    again = tmp_path / "again.json"
    result = run_view(config, xvfb, *options, probe=again)
    assert result.returncode == 0, result.stderr
    restored = json.loads(again.read_text())
    assert restored["view"] == record["view"] and restored["panels"] == record["panels"]


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
    probe = tmp_path / "probe.json"
    result = run_view(
        tmp_path / "config",
        xvfb,
        *("--method", "hwconv", "--hide-panels", "--frames", "3", "--screenshot", str(shot)),
        probe=probe,
    )
    assert result.returncode == 0, result.stderr
    record = json.loads(probe.read_text())
    width, height = record["window_size"]
    assert record["view"] == {"x": 0.0, "y": 0.0, "width": width, "height": height}
    assert record["viewport"] == [0, 0, *record["buffer_size"]]
    screen = read_image(shot)[..., :3]
    session = RenderSession(build_scene())
    try:
        session.render_offscreen("hwconv", (screen.shape[1], screen.shape[0]))
        displayed = session.read_ldr()
    finally:
        session.release()
    np.testing.assert_array_equal(np.round(screen * 255.0), displayed)


def test_the_reference_in_the_window_shows_no_black_reflector_after_ten_frames(xvfb, tmp_path):
    """Issue 28: the reference's first pass covers the reflector from the first frames on.
    After 10 frames (the first batch far from done) every reflector pixel shown black under
    the non-black studio environment is one the reference's own estimate makes black: on
    silhouettes, where every footprint point's shading normal faces away (as in a path
    tracer; shaders/reference/accumulate.glsl), its first whole batch is black too."""
    config = tmp_path / "config"
    config.mkdir()
    (config / "settings.json").write_text(json.dumps({"window_size": [960, 600]}))
    shot = tmp_path / "shot.png"
    probe = tmp_path / "probe.json"
    result = run_view(
        config,
        xvfb,
        *("--method", "reference", "--frames", "10", "--screenshot", str(shot)),
        probe=probe,
    )
    assert result.returncode == 0, result.stderr
    assert envstudio_lines(result.stderr) == []
    record = json.loads(probe.read_text())
    size = tuple(record["render_size"])
    view = view_pixels(np.round(read_image(shot)[..., :3] * 255.0), record)

    session = RenderSession(build_scene())
    try:
        assert session.scene.environment.radiance.max(axis=-1).min() > 0.0, "a black texel"
        reference = session.method("reference")
        session.render_offscreen(reference, size)  # one whole batch, no frame budget
        assert reference.status.batches == 1
        estimate_black = session.read_ldr().max(axis=-1) == 0
        session.renderer.display["background"] = False
        session.render_offscreen("mirror", size)
        reflector = session.read_hdr().sum(axis=-1) > 0.0
    finally:
        session.release()
    shown_black = reflector & (view.max(axis=-1) == 0)
    assert shown_black.sum() < 1e-3 * reflector.sum()
    # on the silhouette a pixel's few footprint samples may all face away in the window's
    # batch and not in the headless one (CI, loaded: another band split): allowed there only
    inner = reflector.copy()
    inner[1:-1, 1:-1] &= reflector[:-2, 1:-1] & reflector[2:, 1:-1]
    inner[1:-1, 1:-1] &= reflector[1:-1, :-2] & reflector[1:-1, 2:]
    # at most a few isolated interior pixels (1e-4 of the reflector) whose window samples so far
    # all came back black where the headless batch's did not (seen once in five loaded CI runs)
    wrong = np.argwhere(shown_black & ~estimate_black & inner)
    allowed = max(1, int(1e-4 * reflector.sum()))
    assert len(wrong) <= allowed, f"black in the window, not in the estimate: {wrong[:10].tolist()}"


def matched_session(names: list[str]) -> RenderSession:
    """A headless session of the default scene whose methods ``names`` are set up as the grid
    sets them: glossiness matched to the first (the method on show) through the reference's
    Phong exponent, cameras steered; each rendered once (so bakes are made and cached, as
    for a user's second run)."""
    session = RenderSession(build_scene())
    methods = {name: session.method(name) for name in names}
    hub = session.method(ground_truth_class().name)
    cube = session.gpu_scene.cube_size
    GlossinessLink().follow(list(methods.values()), methods[names[0]], hub, cube)
    for method in methods.values():
        method.steer_camera(session.camera)
    for name in names:
        session.render_offscreen(name, (32, 32))
    return session


def test_the_grid_view_tiles_every_method_each_as_its_headless_render(xvfb, tmp_path):
    """Issue 29: `view --grid` tiles every method under one camera, in the docked view;
    outside its label each tile is, pixel for pixel, the method rendered headless at the
    tile's size. The bakes (rsibr's sphere maps) are cached first, so every tile shows its
    finished method; the reference, progressive, shows its first frames. F12 on the last
    frame captures the grid as one PNG with the labels: the view's pixels on screen."""
    config = tmp_path / "config"
    config.mkdir()
    (config / "settings.json").write_text(json.dumps({"window_size": [960, 600]}))
    shot = tmp_path / "grid.png"
    probe = tmp_path / "probe.json"
    names = list(available_methods())
    session = matched_session(names)
    try:
        result = run_view(
            config,
            xvfb,
            *("--method", names[0], "--grid", "--frames", "3", "--screenshot", str(shot)),
            probe=probe,
            env={"ENVSTUDIO_PROBE_KEY": "2,F12", "XDG_PICTURES_DIR": str(tmp_path / "pictures")},
        )
        assert result.returncode == 0, result.stderr
        assert envstudio_lines(result.stderr) == [], "a tile reported an error"
        record = json.loads(probe.read_text())
        tiles = record["grid"]["tiles"]
        headless = {}
        for tile in tiles:
            session.render_offscreen(tile["name"], tuple(tile["size"]))
            headless[tile["name"]] = session.read_ldr()
    finally:
        session.release()
    grid = record["grid"]
    assert grid["on"] and grid["fraction"] == 1.0 and grid["status"] is None
    assert [tile["name"] for tile in tiles] == names

    # the tiles lie inside the view, apart, each rendered at its viewport's size
    vx, vy, vw, vh = record["viewport"]
    for i, tile in enumerate(tiles):
        x, y, w, h = tile["viewport"]
        assert tile["size"] == [w, h]
        assert vx <= x and vy <= y and x + w <= vx + vw and y + h <= vy + vh
        for other in tiles[i + 1 :]:
            ox, oy, ow, oh = other["viewport"]
            assert x + w <= ox or ox + ow <= x or y + h <= oy or oy + oh <= y

    image = np.round(read_image(shot)[..., :3] * 255.0).astype(np.int16)
    (capture,) = (tmp_path / "pictures" / "envmap-studio").glob("*-grid-*.png")
    np.testing.assert_array_equal(
        np.round(read_image(capture)[..., :3] * 255.0), view_pixels(image, record)
    )
    for tile, label in zip(tiles, grid["labels"], strict=True):
        name = tile["name"]
        shown = view_pixels(image, {"viewport": tile["viewport"]})
        x, y, w, h = tile["viewport"]
        top = image.shape[0] - (y + h)
        outside = np.ones(shown.shape[:2], dtype=bool)  # the label's box (points = pixels)
        lx, ly, lw, lh = label
        outside[
            max(int(ly) - top, 0) : int(np.ceil(ly + lh)) - top,
            max(int(lx) - x, 0) : int(np.ceil(lx + lw)) - x,
        ] = False
        assert 0.6 < outside.mean() < 1.0, f"{name}: no label or a huge one"
        assert shown[~outside].std() > 10.0, f"{name}: no text in its label"
        if name == "reference":  # progressive: its first frames, not the headless batch
            assert shown[outside].std() > 10.0
            continue
        np.testing.assert_array_equal(shown[outside], headless[name][outside], err_msg=name)


def test_clicking_a_grid_tile_makes_its_method_the_main_view(xvfb, tmp_path):
    """Issue 29: a click (press and release through the viewer's input handlers) on the
    hwconv tile leaves the grid with hwconv shown alone, at the whole view's size."""
    config = tmp_path / "config"
    config.mkdir()
    (config / "settings.json").write_text(json.dumps({"window_size": list(WINDOW)}))
    probe = tmp_path / "probe.json"
    # panels hidden: the view is the window, so the tiles are known before the run
    tiles = tile_layout(["mirror", "hwconv"], (0, 0, *WINDOW))
    x, y, w, h = tiles[1].viewport  # GL pixels = points here; the centre from the top-left
    env = {"ENVSTUDIO_PROBE_CLICK": f"1,{x + w // 2},{WINDOW[1] - (y + h // 2)}"}
    result = run_view(
        config,
        xvfb,
        *("--method", "mirror", "--grid", "mirror,hwconv", "--hide-panels", "--frames", "2"),
        probe=probe,
        env=env,
    )
    assert result.returncode == 0, result.stderr
    record = json.loads(probe.read_text())
    assert record["method"] == "hwconv"
    assert not record["grid"]["on"] and record["render_size"] == list(WINDOW)


def test_kautz_matched_beyond_a_tiles_range_is_clamped_not_an_exit(xvfb, tmp_path):
    """With fresh settings `view --method kautz --grid` exited with status 2: kautz's b = 1.7
    on the 256² cube matches N ≈ 8651, which the grid copied unclamped to rsibr (N in
    [1, 5000]). Every tile renders, each value inside its declared range; the split screen
    against rsibr says the match was clamped."""
    runs = {}
    for run, view in {"grid": ("--grid",), "split": ("--compare", "rsibr")}.items():
        config, probe = tmp_path / run, tmp_path / f"{run}.json"
        config.mkdir()
        options = ("--method", "kautz", *view, "--hide-panels", "--frames", "2")
        result = run_view(config, xvfb, *options, probe=probe)
        assert result.returncode == 0, result.stderr
        assert envstudio_lines(result.stderr) == [], result.stderr
        runs[run] = json.loads(probe.read_text())
    grid = runs["grid"]["grid"]
    assert grid["on"] and [tile["name"] for tile in grid["tiles"]] == list(available_methods())
    for tile in grid["tiles"]:
        for declared in method_class(tile["name"]).parameters:
            if declared.kind == "float" and declared.maximum is not None:
                value = tile["values"][declared.name]
                assert declared.minimum <= value <= declared.maximum, (tile["name"], declared)
    tiles = {tile["name"]: tile["values"] for tile in grid["tiles"]}
    assert tiles["kautz"]["lod_bias"] == 1.7 and tiles["rsibr"]["phong_exponent"] == 5000.0
    split = runs["split"]
    assert split["compare"]["other"] == "rsibr" and split["method"] == "kautz"
    assert split["match_note"].startswith("N = 5000 (clamped from 8651)"), split["match_note"]


def changed_values(method: str) -> dict[str, object]:
    """Non-default values of ``method``'s colours and of its first float parameter (a
    slider: no rebake), from its declarations."""
    values: dict[str, object] = {}
    sliders = [p for p in method_class(method).parameters if p.kind == "float"]
    for parameter in method_class(method).parameters:
        if parameter.kind == "color":
            values[parameter.name] = [0.25, 0.5, 0.75]
    if sliders:
        slider = sliders[0]
        values[slider.name] = slider.default + 0.25 * (slider.maximum - slider.default)
    return values


@pytest.mark.parametrize("method", list(available_methods()))
def test_the_viewer_starts_again_from_every_setting_it_saved(xvfb, tmp_path, method):
    """Issue 38 item 1: a settings file with every persisted setting away from its default
    (the grid on at 1/2 size with two methods picked, as the grid's 200 ms rule leaves it on
    a slow machine; a split screen; the saved method's values; the display; the camera;
    the docking layout; the panels hidden) restarts the viewer, which shows that state and
    saves it back unchanged."""
    config = tmp_path / "config"
    config.mkdir()
    first = run_view(config, xvfb, "--method", method, "--frames", "1")
    assert first.returncode == 0, first.stderr
    saved = json.loads((config / "settings.json").read_text())
    assert "[Docking][Data]" in saved["imgui_ini"]
    others = [name for name in available_methods() if name != method]
    picked = [name for name in available_methods() if name in (method, others[0])]
    values = changed_values(method)
    saved |= {
        "method": method,
        "method_values": {method: values},
        "display": {"exposure": 1.5, "tonemap": "reinhard", "background": False},
        "camera": {"azimuth": 40.0, "elevation": 25.0, "distance": 4.0, "target": [0, 0, 0]},
        "grid": {"on": True, "picked": picked, "scale": 1},
        "compare": {
            "other": others[1],
            "split": False,
            "divider": 0.3,
            "heat": True,
            "heat_scale": 0.5,
        },
        "panels_shown": False,
        "match_glossiness": False,
    }
    (config / "settings.json").write_text(json.dumps(saved))
    probe = tmp_path / "probe.json"

    result = run_view(config, xvfb, "--frames", "2", probe=probe)

    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr and envstudio_lines(result.stderr) == []
    record = json.loads(probe.read_text())
    assert record["method"] == method and not record["panels_shown"]
    assert record["grid"]["on"] and record["grid"]["fraction"] == 0.5
    assert record["grid"]["status"].startswith("grid at 1/2 size")
    assert [tile["name"] for tile in record["grid"]["tiles"]] == picked
    assert record["compare"] == saved["compare"]
    assert record["display"] == saved["display"]
    assert record["camera"] == [40.0, 25.0]
    for name, value in values.items():
        assert record["values"][name] == pytest.approx(value), name
    again = json.loads((config / "settings.json").read_text())
    for key in ("method", "display", "grid", "compare", "panels_shown", "match_glossiness"):
        assert again[key] == saved[key], key
    assert again["method_values"][method] | values == again["method_values"][method]


def test_the_grids_labels_give_compares_exact_numbers_in_the_window(xvfb, tmp_path):
    """Issue 40 item 5: in the real window, once the view stays still, the hwconv and mirror
    tiles' labels give their error against the exact reference, and the numbers equal
    compare's (--reference exact, trace=false, the tile's size and the grid's ssaa)."""
    from envstudio.measure.compare import method_classes, plan_parameters, run_comparison
    from envstudio.measure.exact_tiles import SSAA
    from envstudio.measure.reference_runs import EXACT

    config = tmp_path / "config"
    config.mkdir()
    (config / "settings.json").write_text(json.dumps({"window_size": [160, 96]}))
    probe = tmp_path / "probe.json"
    names = ["hwconv", "mirror"]
    result = run_view(
        config,
        xvfb,
        *("--method", "hwconv", "--grid", ",".join(names), "--hide-panels", "--frames", "80"),
        probe=probe,
        env={"ENVSTUDIO_PROBE_FRAME_MS": "100"},
    )
    assert result.returncode == 0, result.stderr
    grid = json.loads(probe.read_text())["grid"]
    (size,) = {tuple(tile["size"]) for tile in grid["tiles"]}
    session = matched_session(names)
    try:
        exponent = session.method("hwconv").values["phong_exponent"]
        plan = plan_parameters(
            method_classes(names), ["trace=false", f"phong_exponent={exponent!r}"]
        )
        comparison = run_comparison(
            session, names, size, plan, frames=1, warmup=0, ssaa=SSAA, reference_kind=EXACT
        )
    finally:
        session.release()
    for row in comparison.results:
        numbers = grid["numbers"][row.name]
        assert numbers["against"] == f"exact {size[0]}×{size[1]}", numbers
        assert numbers["relative_error"] == pytest.approx(row.median_relative_error, abs=1e-3)
        assert numbers["psnr_db"] == pytest.approx(row.metrics.psnr_db, abs=1e-3)


def test_the_window_keeps_drawing_while_the_glossiness_curve_is_measured(xvfb, tmp_path):
    """Issue 40 item 5: the Compare panel's curve is measured by a child process. From the
    measurement's start to its first point (mirror at N = 20: its exact reference takes
    about a second here, which measuring between frames stalled the window for) the window
    keeps drawing frames, none of them late; closing the window with the second point still
    being measured ends the viewer at once, its child and its threads gone."""
    config = tmp_path / "config"
    config.mkdir()
    (config / "settings.json").write_text(json.dumps({"window_size": list(WINDOW)}))
    probe = tmp_path / "probe.json"
    result = run_view(
        config,
        xvfb,
        *("--method", "mirror", "--frames", "1500"),
        probe=probe,
        env={"ENVSTUDIO_PROBE_CURVE": "2;mirror;20,50;32", "ENVSTUDIO_PROBE_FRAME_MS": "30"},
    )
    ended_at = time.time()
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr and "leaked" not in result.stderr
    curve = json.loads(probe.read_text())["curve"]
    frames = np.array(curve["frames"])
    measuring = frames[(frames[:, 2] == 1) & (frames[:, 1] == 0)]
    assert frames[-1, 1] == 1, "the window closed before the first point"
    assert len(measuring) >= 20, f"{len(measuring)} frames while measuring"
    gaps = np.diff(frames[:, 0])
    assert gaps.max() < 0.5, f"a frame {gaps.max():.2f} s after the one before"
    assert ended_at - curve["closed_at"] < 5.0, "the viewer took long to end"
    assert curve["children_after"] == 0 and curve["threads_after"] == 1
