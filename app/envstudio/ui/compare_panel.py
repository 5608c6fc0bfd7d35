"""The Compare panel: split screen against another method and the error heat map.

The state lives in :class:`CompareState`; the panel edits it in place and the
app renders through :class:`envstudio.engine.split_view.SplitView` while a
second method is chosen. The divider can be dragged in the 3D view.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

from imgui_bundle import imgui

from envstudio.core.colormap import magma
from envstudio.engine.method import Method
from envstudio.engine.split_view import SplitSettings
from envstudio.ui.docking import PANEL_FLAGS
from envstudio.ui.error_plot import GlossinessCurve, glossiness_section
from envstudio.ui.grid import GridState, grid_section

OFF = "off"
"""Combo entry for no comparison."""
GRAB_PIXELS = 6.0
"""How close to the divider (window points) a press grabs it."""


@dataclass
class CompareState:
    """What the compare view shows and whether the divider is being dragged."""

    other: str | None = None
    settings: SplitSettings = field(default_factory=SplitSettings)
    dragging: bool = False
    match: bool = True
    match_note: str | None = None

    def as_settings(self) -> dict:
        """What the settings file keeps: the other method (None: no split) and the split."""
        return {"other": self.other, **asdict(self.settings)}

    def restore(self, saved: object, methods: list[str]) -> list[str]:
        """Apply :meth:`as_settings`' table from the settings file; returns what was rejected.

        A method no longer registered is dropped silently (a plugin may be gone).
        """
        if not isinstance(saved, dict):
            return [f"compare = {saved!r}, expected a table"]
        problems = []
        other = saved.get("other")
        if other is None or isinstance(other, str):
            self.other = other if other in methods else None
        else:
            problems.append(f"compare.other = {other!r}, expected a method name")
        for flag in ("split", "heat"):
            value = saved.get(flag, getattr(self.settings, flag))
            if isinstance(value, bool):
                setattr(self.settings, flag, value)
            else:
                problems.append(f"compare.{flag} = {value!r}, expected true or false")
        for name, low, high in (("divider", 0.0, 1.0), ("heat_scale", 1e-3, 10.0)):
            value = saved.get(name, getattr(self.settings, name))
            if (
                isinstance(value, (int, float))
                and not isinstance(value, bool)
                and low <= value <= high
            ):
                setattr(self.settings, name, float(value))
            else:
                problems.append(f"compare.{name} = {value!r}, expected {low:g} to {high:g}")
        return problems

    def grab(self, x: float, view_width: float) -> bool:
        """Start dragging if a press at ``x`` (from the 3D view's left edge) is on the divider;
        returns whether it was."""
        on_divider = abs(x - self.settings.divider * view_width) <= GRAB_PIXELS
        self.dragging = bool(self.other and self.settings.split and on_divider)
        return self.dragging

    def drag(self, x: float, view_width: float) -> None:
        """Move the divider to ``x`` (from the 3D view's left edge) while dragging."""
        if self.dragging and view_width > 0:
            self.settings.divider = min(max(x / view_width, 0.0), 1.0)


def compare_panel(
    methods: dict[str, type[Method]],
    current: str,
    state: CompareState,
    grid: GridState | None = None,
    curve: GlossinessCurve | None = None,
    exponent: float | None = None,
) -> str | None:
    """Edit ``state``: the method compared against, split, divider, heat map and its scale;
    with ``grid``, the grid view and the methods it tiles (the grid wins over the split);
    with ``curve``, the error-against-glossiness plot, ``exponent`` (the current N) marked.
    Returns the method whose curve was clicked, or None."""
    picked = None
    if imgui.begin("Compare", None, PANEL_FLAGS)[0]:
        names = [OFF, *(n for n in methods if n != current)]
        chosen = state.other if state.other in names else OFF
        imgui.set_next_item_width(-1.0)
        changed, index = imgui.combo("##other", names.index(chosen), names)
        if changed:
            state.other = None if names[index] == OFF else names[index]
        imgui.set_item_tooltip("Method B, shown right of the divider and used by the heat map.")
        state.match = imgui.checkbox("match glossiness", state.match)[1]
        imgui.set_item_tooltip(
            "Keep f_λ, k_d and the look of the blur when switching methods, for B and in the\n"
            "grid: when one method's value changes, the others follow through one Phong\n"
            "exponent N, as compare matches (LOD bias b <-> N by the fitted mapping,\n"
            "prefilter/glossiness.py; GGX alpha = sqrt(2 / (4N + 2))). Off: each keeps its own."
        )
        if state.match and state.match_note:
            imgui.text_wrapped(state.match_note)
        if state.other:
            settings = state.settings
            settings.split = imgui.checkbox("split screen", settings.split)[1]
            changed, value = imgui.slider_float("divider", settings.divider, 0.0, 1.0)
            if changed:
                settings.divider = value
            settings.heat = imgui.checkbox("error heat map (A vs B)", settings.heat)[1]
            changed, value = imgui.slider_float(
                "scale", settings.heat_scale, 0.01, 2.0, "%.2f", imgui.SliderFlags_.logarithmic
            )
            if changed:
                settings.heat_scale = value
            if settings.heat:
                _colour_bar(settings.heat_scale)
        if grid is not None:
            grid_section(list(methods), grid)
        if curve is not None:
            picked = glossiness_section(curve, list(methods), exponent)
    imgui.end()
    return picked


def _colour_bar(scale: float, steps: int = 32) -> None:
    """The heat map's colour scale, 0 to ``scale`` relative error, drawn with the draw list."""
    draw = imgui.get_window_draw_list()
    x, y = imgui.get_cursor_screen_pos()
    width = imgui.get_content_region_avail().x
    height = 14.0
    for i in range(steps):
        r, g, b = magma((i + 0.5) / steps)
        colour = imgui.get_color_u32((float(r), float(g), float(b), 1.0))
        x0 = x + width * i / steps
        draw.add_rect_filled((x0, y), (x0 + width / steps + 1.0, y + height), colour)
    imgui.dummy((width, height))
    imgui.text(f"0 %{'':>28}{100 * scale:.0f} % relative error")
