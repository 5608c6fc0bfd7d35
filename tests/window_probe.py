"""Run the real viewer (``envstudio view ARGS``) and write what its last frame laid out as JSON.

    python tests/window_probe.py OUT.json view [VIEW OPTIONS...]

The viewer runs unchanged; a subclass only records, after each frame, the 3D view's
rectangle (the dock space's central node, points), its GL viewport (framebuffer
pixels, origin bottom-left), the size the scene was rendered at, the window and
framebuffer sizes, and each panel's window rectangle, whether it is docked and
whether it is on show (a tab behind another is not).
The window tests (tests/test_window_smoke.py) read it beside the screenshot.
"""

from __future__ import annotations

import json
import sys
from dataclasses import asdict
from typing import ClassVar

from imgui_bundle.imgui import internal

import envstudio.ui.app as app
from envstudio.cli import main
from envstudio.ui.docking import PANELS, gl_viewport


class ProbedViewer(app.Viewer):
    """The viewer, recording its layout after every frame."""

    record: ClassVar[dict] = {}

    def on_render(self, time: float, frametime: float) -> None:
        super().on_render(time, frametime)
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
        ProbedViewer.record = {
            "frames": self.frames_drawn,
            "panels_shown": self.panels_shown,
            "view": asdict(self.view),
            "viewport": list(gl_viewport(self.view, self.wnd.size, self.wnd.buffer_size)),
            "render_size": list(hdr.size) if hdr is not None else None,
            "window_size": list(self.wnd.size),
            "buffer_size": list(self.wnd.buffer_size),
            "panels": panels,
            "method": self.method_name,
        }


def probe(out: str, argv: list[str]) -> int:
    app.Viewer = ProbedViewer
    status = main(argv)
    with open(out, "w", encoding="utf-8") as file:
        json.dump(ProbedViewer.record, file)
    return status


if __name__ == "__main__":
    sys.exit(probe(sys.argv[1], sys.argv[2:]))
