"""The UI font: Droid Sans from imgui-bundle's assets.

ImGui's built-in ProggyClean covers ASCII only, but method titles and units use
Greek letters and typographic signs (``f_λ``, "Blinn–Newell", "1 − F").
Droid Sans covers them; with ImGui 1.92's dynamic atlas every glyph is
rasterised on first use, so no glyph ranges are declared.
"""

from __future__ import annotations

from pathlib import Path

import imgui_bundle
from imgui_bundle import imgui

FONT_FILE = Path(imgui_bundle.__file__).parent / "assets" / "fonts" / "DroidSans.ttf"
FONT_SIZE = 15.0


def load_ui_font() -> None:
    """Make Droid Sans the default font of the current ImGui context (if the file exists)."""
    if FONT_FILE.is_file():
        imgui.get_io().fonts.add_font_from_file_ttf(str(FONT_FILE), FONT_SIZE)
