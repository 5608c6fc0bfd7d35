"""The viewer tour's screenshots: the real viewer (``envstudio view``), run once under the
X server named by ``DISPLAY``, following :data:`STEPS` and saving the window at each.

    python viewer_tour.py OUT_DIR

The viewer runs unchanged (as tests/window_probe.py runs it); a subclass only acts before
some frames — through the viewer's own key handler where a key does it (Tab, F12, the
number keys), else as the panel's control does (the Compare panel's method B and its grid
view checkbox) — and reads the window after others, as ``--screenshot`` does. It writes
``OUT_DIR/NAME.png`` per shot (the whole window, or the 3D view alone), the PNG that F12
saved as ``OUT_DIR/capture-file.png`` and ``OUT_DIR/tour.json``: per shot its frame, the
seconds since the first frame began, the method on show and that method's status line (the
reference's samples and noise). The settings and captures folders are the caller's
(``ENVSTUDIO_CONFIG_DIR``, ``XDG_PICTURES_DIR``); the settings give the window's size and
the reference's values.
"""

from __future__ import annotations

import json
import shutil
import sys
import time as clock
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np
from imgui_bundle import imgui

import envstudio.ui.app as app
from envstudio.cli import main
from envstudio.engine.registry import available_methods
from envstudio.ui.capture import default_captures_dir, read_framebuffer, save
from envstudio.ui.docking import gl_viewport

FIRST = "hwconv"
"""The method on show first (its panel has sliders and choices)."""

Action = Callable[[app.Viewer], None]


def key(name: str) -> Action:
    """Press and release key ``name`` (moderngl-window's name) through the viewer."""

    def press(viewer: app.Viewer) -> None:
        keys = viewer.wnd.keys
        for action in (keys.ACTION_PRESS, keys.ACTION_RELEASE):
            viewer.on_key_event(getattr(keys, name), action, viewer.wnd.modifiers)

    return press


def number_key(method: str) -> Action:
    """The number key that picks ``method`` (1–9, in registration order)."""
    return key(f"NUMBER_{list(available_methods()).index(method) + 1}")


def compare_with(method: str | None) -> Action:
    """The Compare panel's combo: method B (None: off); the split screen on."""

    def choose(viewer: app.Viewer) -> None:
        viewer.compare.other = method
        viewer.compare.settings.split = True

    return choose


def grid_view(viewer: app.Viewer) -> None:
    """The Compare panel's 'grid view' checkbox, ticked (no method picked: every method)."""
    viewer.grid.enter()


def capture_tab(viewer: app.Viewer) -> None:
    """Bring the Capture panel's tab to the front, as a click on it does."""
    imgui.set_window_focus("Capture")


def click_tile(method: str) -> Action:
    """A left click, through the viewer's mouse handlers, in the middle of ``method``'s tile of
    the grid (which then shows that method alone)."""

    def click(viewer: app.Viewer) -> None:
        tile = next(t for t in viewer.grid.tiles if t.name == method)
        x, y, w, h = tile.viewport  # GL pixels from the bottom; points = pixels under Xvfb
        at = (x + w // 2, viewer.wnd.buffer_size[1] - (y + h // 2))
        left = viewer.wnd.mouse.left
        viewer.on_mouse_position_event(*at, 0, 0)
        viewer.on_mouse_press_event(*at, left)
        viewer.on_mouse_release_event(*at, left)

    return click


Condition = Callable[[app.Viewer], bool]


def reference_batches(least: int) -> Condition:
    """Whether the reference has accumulated ``least`` whole batches."""
    return lambda viewer: viewer.session.method("reference").status.batches >= least


def no_bake_under_way(viewer: app.Viewer) -> bool:
    """Whether every tile of the grid shows its finished bake (rsibr bakes a few views a
    frame)."""
    methods = [viewer.session.method(tile.name) for tile in viewer.grid.tiles]
    return bool(methods) and all(method.progress() is None for method in methods)


@dataclass
class Step:
    """Run at least ``frames`` frames, the first after ``actions``, and on until ``until`` holds
    (at most :data:`MOST_FRAMES`); then save the window (``view_only``: the 3D view) as
    ``shot`` (None: no shot)."""

    frames: int
    shot: str | None
    actions: list[Action] = field(default_factory=list)
    until: Condition | None = None
    view_only: bool = False


MOST_FRAMES = 300
"""Frames a step waits for its condition at most (then its shot is taken as it is)."""

STEPS = [
    Step(3, "panels"),
    Step(8, "split", [compare_with("reference")]),
    Step(4, "reference-1", [compare_with(None), number_key("reference")], view_only=True),
    Step(1, "reference-2", until=reference_batches(1), view_only=True),
    Step(1, "reference-3", until=reference_batches(3), view_only=True),
    Step(3, "grid", [key("TAB"), grid_view], until=no_bake_under_way),
    Step(1, None, [click_tile(FIRST), key("TAB")]),
    Step(3, "capture", [capture_tab, key("F12")]),
]
"""The tour: the panels; the split screen against the reference; the reference alone,
converging (its view after 4 frames, after its first whole batch, after three); the grid
(panels hidden) once no tile is baking; a click on a tile and the panels again; then the
Capture panel's tab in front (a frame later: the panels must exist) and F12."""


STRIP = ("reference-1", "reference-2", "reference-3")
"""Shots put side by side in ``reference.png`` (a gap of :data:`GAP` pixels between them)."""
GAP = 6


class TourViewer(app.Viewer):
    """The viewer, acting and saving the window as :data:`STEPS` say; it closes the window
    after the last."""

    out: ClassVar[Path]
    record: ClassVar[dict[str, dict]] = {}
    shots: ClassVar[dict[str, np.ndarray]] = {}
    step: ClassVar[int] = 0
    step_frames: ClassVar[int] = 0
    started: ClassVar[float | None] = None

    def on_render(self, time: float, frametime: float) -> None:
        if TourViewer.started is None:
            TourViewer.started = clock.perf_counter()
        step = STEPS[TourViewer.step]
        if TourViewer.step_frames == 0:
            for action in step.actions:
                action(self)
        super().on_render(time, frametime)
        TourViewer.step_frames += 1
        if TourViewer.step_frames < step.frames:
            return
        if step.until and not step.until(self) and TourViewer.step_frames < MOST_FRAMES:
            return
        if step.shot:
            self.take(step)
        TourViewer.step, TourViewer.step_frames = TourViewer.step + 1, 0
        if TourViewer.step == len(STEPS):
            self.wnd.close()

    def take(self, step: Step) -> None:
        """Save the window (or the view) as ``step.shot`` and what was on show."""
        screen, size = self.ctx.screen, self.wnd.buffer_size
        if step.view_only:
            viewport = gl_viewport(self.view, self.wnd.size, size)
            pixels = read_framebuffer(screen, viewport[2:], viewport[:2])
        else:
            pixels = read_framebuffer(screen, size)
        save(self.out / f"{step.shot}.png", pixels)
        TourViewer.shots[step.shot] = pixels
        TourViewer.record[step.shot] = {
            "frame": self.frames_drawn,
            "seconds": round(clock.perf_counter() - TourViewer.started, 1),
            "method": self.choice.name,
            "status": self.session.method(self.choice.name).status_line(),
            "size": list(pixels.shape[1::-1]),
        }


def strip(images: list[np.ndarray]) -> np.ndarray:
    """(h, w, 3) uint8: ``images`` (of one height) side by side, white between them."""
    gap = np.full((images[0].shape[0], GAP, 3), 255, np.uint8)
    parts = [part for image in images for part in (gap, image)][1:]
    return np.concatenate(parts, axis=1)


def tour(out: Path) -> int:
    """Run the viewer through :data:`STEPS`; its exit status."""
    out.mkdir(parents=True, exist_ok=True)
    TourViewer.out = out
    app.Viewer = TourViewer
    status = main(["view", "--method", FIRST])
    if status != 0:
        return status
    save(out / "reference.png", strip([TourViewer.shots[name] for name in STRIP]))
    (saved,) = default_captures_dir().glob("*.png")
    shutil.copyfile(saved, out / "capture-file.png")
    TourViewer.record["capture"]["file"] = saved.name
    (out / "tour.json").write_text(json.dumps(TourViewer.record, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(tour(Path(sys.argv[1])))
