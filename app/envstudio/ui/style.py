"""The UI font: Droid Sans from imgui-bundle's assets, Latin Modern Math merged in.

ImGui's built-in ProggyClean covers ASCII only, but method titles, summaries and
units use Greek letters, typographic and mathematical signs (``f_λ``,
"Blinn–Newell", "1 − F", "L_banks(t, ⟨v,t⟩)", "∠(v,t)", "s ∈ [0, 1)"). Droid Sans
covers most; the signs it lacks (∈ ∠ ⟨ ⟩) come from Latin Modern Math, merged into
the same font. With ImGui 1.92's dynamic atlas every glyph is rasterised on first
use, so no glyph ranges are declared.
"""

from __future__ import annotations

from pathlib import Path

import imgui_bundle
from imgui_bundle import imgui

FONTS = Path(imgui_bundle.__file__).parent / "assets" / "fonts"
FONT_FILE = FONTS / "DroidSans.ttf"
#: Merged into the UI font: the mathematical signs Droid Sans lacks.
FALLBACK_FILE = FONTS / "latex" / "latinmodern-math.otf"
FONT_SIZE = 15.0


def load_ui_font() -> imgui.ImFont | None:
    """Make Droid Sans, with Latin Modern Math merged in, the default font of the current
    ImGui context (if the files exist); the font, or None."""
    if not FONT_FILE.is_file():
        return None
    font = imgui.get_io().fonts.add_font_from_file_ttf(str(FONT_FILE), FONT_SIZE)
    if FALLBACK_FILE.is_file():
        merged = imgui.ImFontConfig()
        merged.merge_mode = True
        imgui.get_io().fonts.add_font_from_file_ttf(str(FALLBACK_FILE), FONT_SIZE, merged)
    return font
