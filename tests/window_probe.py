"""Run the real viewer (``envstudio view ARGS``) and write what its last frame laid out as JSON.

    python tests/window_probe.py OUT.json view [VIEW OPTIONS...]

The viewer runs unchanged; a subclass only records, after each frame, the 3D view's
rectangle (the dock space's central node, points), its GL viewport (framebuffer
pixels, origin bottom-left), the size the scene was rendered at, the window and
framebuffer sizes, and each panel's window rectangle, whether it is docked and
whether it is on show (a tab behind another is not).
It records the method on show with its parameter values, the display values, the
camera's azimuth and elevation, the split screen's state and its glossiness match note.
In the grid view it records the tiles (method, GL viewport, render size, parameter
values), the tile fraction, the labels' boxes (window points), each tile's label numbers
and the status line's grid text.
The window tests (tests/test_window_smoke.py) read it beside the screenshot.

``ENVSTUDIO_PROBE_CLICK=FRAME,X,Y`` presses and releases the left button at window
point (X, Y) before frame FRAME (counted from 0) through the viewer's own input
handlers, as the window toolkit would; ``ENVSTUDIO_PROBE_KEY=FRAME,NAME`` presses key NAME
(moderngl-window's name, e.g. F12) before frame FRAME. ``ENVSTUDIO_PROBE_FRAME_MS=MS``
makes each frame last at least MS milliseconds (the grid's timed steps then get a known
wall time from ``--frames``).

``ENVSTUDIO_PROBE_CURVE=FRAME;NAMES;EXPONENTS;SIZE`` (``2;mirror;20,50;32``) starts the
Compare panel's glossiness curve of methods NAMES at Phong exponents EXPONENTS and
SIZE x SIZE pixels before frame FRAME, as its button does, records each frame's wall
time (perf_counter) and the points done from then on, and closes the window in the frame
the first point arrives, the measurement still running. After the viewer has ended it
records the child processes and threads still there.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import sys
import threading
import time as clock
from dataclasses import asdict
from typing import ClassVar

from imgui_bundle.imgui import internal

import envstudio.ui.app as app
from envstudio.cli import main
from envstudio.ui.docking import PANELS, gl_viewport
from envstudio.ui.error_plot import GlossinessCurve


class ProbedViewer(app.Viewer):
    """The viewer, recording its layout after every frame."""

    record: ClassVar[dict] = {}
    curve_frames: ClassVar[list] = []
    """[perf_counter, points done, measuring] after each frame once the curve started."""
    closed_at: ClassVar[float | None] = None
    """time.time() when the probe closed the window on the curve's first point."""

    def on_render(self, time: float, frametime: float) -> None:
        started = clock.perf_counter()
        curve = os.environ.get("ENVSTUDIO_PROBE_CURVE")
        if curve:
            frame, names, exponents, size = curve.split(";")
            if int(frame) == self.frames_drawn:
                n = int(size)
                self.panels.curve = GlossinessCurve(
                    [float(e) for e in exponents.split(",")], (n, n)
                )
                self.panels.curve.start(names.split(","))
        click = os.environ.get("ENVSTUDIO_PROBE_CLICK")
        if click:
            frame, x, y = (int(v) for v in click.split(","))
            if frame == self.frames_drawn:
                left = self.wnd.mouse.left
                self.on_mouse_position_event(x, y, 0, 0)
                self.on_mouse_press_event(x, y, left)
                self.on_mouse_release_event(x, y, left)
        key = os.environ.get("ENVSTUDIO_PROBE_KEY")
        if key:
            frame, name = key.split(",")
            if int(frame) == self.frames_drawn:
                keys = self.wnd.keys
                self.on_key_event(getattr(keys, name), keys.ACTION_PRESS, self.wnd.modifiers)
        super().on_render(time, frametime)
        if curve and self.frames_drawn > int(frame):
            plot = self.panels.curve
            self.curve_frames.append([clock.perf_counter(), plot.done, plot.measuring])
            if plot.done >= 1 and ProbedViewer.closed_at is None:
                ProbedViewer.closed_at = clock.time()
                self.wnd.close()
        hdr = self.session.renderer.hdr_texture
        panels = {}
        for name in PANELS:
            window = internal.find_window_by_name(name)
            if window is not None:
                panels[name] = {
                    "rect": [window.pos.x, window.pos.y, window.size.x, window.size.y],
                    "docked": window.dock_node is not None,
                    "shown": window.active and not window.hidden and not window.skip_items,
                }
        labels = self.view_renderer.grid_labels if self.grid.on else []
        ProbedViewer.record = {
            "frames": self.frames_drawn,
            "panels_shown": self.panels_shown,
            "view": asdict(self.view),
            "viewport": list(gl_viewport(self.view, self.wnd.size, self.wnd.buffer_size)),
            "render_size": list(hdr.size) if hdr is not None else None,
            "window_size": list(self.wnd.size),
            "buffer_size": list(self.wnd.buffer_size),
            "panels": panels,
            "method": self.choice.name,
            "values": self.session.method(self.choice.name).values.as_dict(),
            "display": self.session.renderer.display.as_dict(),
            "camera": [self.session.camera.azimuth, self.session.camera.elevation],
            "compare": self.compare.as_settings(),
            "match_note": self.compare.match_note,
            "grid": {
                "on": self.grid.on,
                "fraction": self.grid.scale.fraction,
                "tiles": [
                    {
                        "name": t.name,
                        "viewport": list(t.viewport),
                        "size": list(t.render_size),
                        "values": self.session.method(t.name).values.as_dict(),
                    }
                    for t in self.grid.tiles
                ],
                "labels": [list(box) for box in labels],
                "numbers": {name: asdict(n) for name, n in self.grid.numbers.items()},
                "status": self.status.mode_text,
            },
        }
        least_ms = float(os.environ.get("ENVSTUDIO_PROBE_FRAME_MS", "0"))
        clock.sleep(max(0.0, least_ms / 1e3 - (clock.perf_counter() - started)))


def probe(out: str, argv: list[str]) -> int:
    app.Viewer = ProbedViewer
    status = main(argv)
    if ProbedViewer.curve_frames:
        ProbedViewer.record["curve"] = {
            "frames": ProbedViewer.curve_frames,
            "closed_at": ProbedViewer.closed_at,
            "children_after": len(multiprocessing.active_children()),
            "threads_after": threading.active_count(),
        }
    with open(out, "w", encoding="utf-8") as file:
        json.dump(ProbedViewer.record, file)
    return status


if __name__ == "__main__":
    sys.exit(probe(sys.argv[1], sys.argv[2:]))
