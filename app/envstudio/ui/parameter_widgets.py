"""ImGui widgets built from parameter declarations, holding no copy of the state.

Each widget reads the current value from a :class:`ParameterValues` and, when
the user changes it, assigns it back (``values[name] = v``), where the
declaration validates it::

    float   slider_float over [minimum, maximum], logarithmic when ``log``
            (drag_float without a range)
    int     slider_int over [minimum, maximum], logarithmic when ``log``
            (drag_int without a range)
    bool    checkbox
    choice  combo of ``choices``
    path    a text field (applied on Enter) and an "Open..." button for a native
            file dialog offering the suffixes in ``choices``
    color   color_edit3 (linear RGB; values past 1 for an unbounded maximum) with a
            scalar slider beside it that scales all three channels together (its
            value the channels' mean; from black, a grey), and a preset combo when
            the declaration has presets (``fresnel``'s metals and dielectrics)

The unit and help text form the tooltip. A number typed past its range
(Ctrl+click on a slider) is clamped to it and the clamp is noted in the status line.
"""

from __future__ import annotations

from imgui_bundle import imgui

from envstudio.core.parameters import Parameter, ParameterValues
from envstudio.errors import UserError
from envstudio.ui.file_dialogs import OpenFileDialog
from envstudio.ui.status import StatusLine

_PATH_DIALOGS: dict[str, OpenFileDialog] = {}
"""One open-file dialog per ``path`` parameter name, polled every frame."""

_CLAMP = imgui.SliderFlags_.none
"""Sliders do not clamp typed values themselves, so that a clamp can be noted."""
_FLOAT = "%.4g"


def tooltip(param: Parameter) -> str:
    """Help text followed by the unit, e.g. ``"Schlick reflectance ... [f_λ]"``."""
    unit = f" [{param.unit}]" if param.unit else ""
    return f"{param.help}{unit}".strip()


def clamp_note(param: Parameter, value):
    """``value`` clamped to the range of ``param``, and a note when it was out of it.

    Returns
    -------
    value
        The value, inside ``[minimum, maximum]`` for bounded numbers.
    str or None
        ``"phong_exponent 9000 is out of [1, 5000]: clamped to 5000"``, or None.
    """
    if param.kind not in ("float", "int") or param.minimum is None or param.maximum is None:
        return value, None
    clamped = min(max(value, param.minimum), param.maximum)
    if clamped == value:
        return value, None
    clamped = type(value)(clamped)
    return clamped, (
        f"{param.name} {value:g} is out of [{param.minimum:g}, {param.maximum:g}]: "
        f"clamped to {clamped:g}"
    )


def parameter_widget(values: ParameterValues, param: Parameter) -> str | None:
    """Draw the widget of ``param`` and assign the value the user gives it.

    Numbers declared without a range get a drag field instead of a slider.

    Returns
    -------
    str or None
        A note when the value typed was out of range and was clamped (:func:`clamp_note`).

    Raises
    ------
    ParameterError
        If the declaration rejects the value the widget produced.
    """
    label = param.name
    current = values[param.name]
    if not param.applies(values):  # greyed out: it changes nothing under the others' values
        imgui.begin_disabled()
        try:
            return _widget(values, param, label, current)
        finally:
            imgui.end_disabled()
    return _widget(values, param, label, current)


def _widget(values: ParameterValues, param: Parameter, label: str, current) -> str | None:
    """The widget of :func:`parameter_widget`, drawn."""
    bounded = param.minimum is not None and param.maximum is not None
    if param.kind == "float" and bounded:
        flags = _CLAMP | (imgui.SliderFlags_.logarithmic if param.log else 0)
        changed, value = imgui.slider_float(
            label, float(current), float(param.minimum), float(param.maximum), _FLOAT, flags
        )
    elif param.kind == "float":
        changed, value = imgui.drag_float(label, float(current), 0.01, 0.0, 0.0, _FLOAT)
    elif param.kind == "int" and bounded:
        flags = _CLAMP | (imgui.SliderFlags_.logarithmic if param.log else 0)
        changed, value = imgui.slider_int(
            label, int(current), int(param.minimum), int(param.maximum), "%d", flags
        )
    elif param.kind == "int":
        changed, value = imgui.drag_int(label, int(current))
    elif param.kind == "bool":
        changed, value = imgui.checkbox(label, bool(current))
    elif param.kind == "path":
        changed, value = _path_widget(param, str(current))
    elif param.kind == "color":
        changed, value = _color_widget(param, tuple(current))
    else:
        index = param.choices.index(current)
        changed, index = imgui.combo(label, index, list(param.choices))
        value = param.choices[index]
    text = tooltip(param)
    if text and param.kind != "color":  # the colour's items have their own
        imgui.set_item_tooltip(text)
    note = None
    if changed:
        value, note = clamp_note(param, value)
        values[param.name] = value
    return note


def scaled_color(
    rgb: tuple[float, float, float], mean: float, maximum: float | None
) -> tuple[float, float, float]:
    """``rgb`` scaled so that its channels' mean becomes ``mean`` (the colour kept, each
    channel clamped to ``maximum``); black becomes the grey ``mean``."""
    old = sum(rgb) / 3.0
    high = float("inf") if maximum is None else maximum
    if old <= 0.0:
        return (min(mean, high),) * 3
    return tuple(min(c * mean / old, high) for c in rgb)


def _color_widget(param: Parameter, current: tuple) -> tuple[bool, tuple[float, float, float]]:
    """color_edit3, the scalar slider beside it and the preset combo; (changed, value)."""
    width = imgui.calc_item_width()
    spacing = imgui.get_style().item_inner_spacing.x
    hdr = imgui.ColorEditFlags_.hdr if param.maximum is None or param.maximum > 1 else 0
    imgui.push_id(param.name)
    imgui.set_next_item_width(0.65 * width)
    changed, rgb = imgui.color_edit3(
        "##rgb", list(current), flags=hdr | imgui.ColorEditFlags_.float
    )
    value = tuple(float(c) for c in rgb)
    text = tooltip(param)
    if text:
        imgui.set_item_tooltip(text)
    imgui.same_line(0.0, spacing)
    imgui.set_next_item_width(max(0.35 * width - spacing, 1.0))
    mean = sum(value) / 3.0
    low = 0.0 if param.minimum is None else float(param.minimum)
    if param.maximum is None:
        moved, mean = imgui.drag_float(param.name, mean, 0.01, low, 0.0, _FLOAT)
    else:
        moved, mean = imgui.slider_float(param.name, mean, low, float(param.maximum), _FLOAT)
    if moved:
        value = scaled_color(value, max(mean, low), param.maximum)
    if text:
        imgui.set_item_tooltip(f"All three channels together: their mean. {text}")
    picked = False
    if param.presets:
        names = [name for name, _ in param.presets]
        shown = next((name for name, rgb in param.presets if rgb == value), "custom")
        imgui.set_next_item_width(0.65 * width)
        if imgui.begin_combo("preset", shown):
            for name, preset in param.presets:
                if imgui.selectable(name, name == shown)[0]:
                    value, picked = preset, True
            imgui.end_combo()
        imgui.set_item_tooltip(f"{param.name}: one of {', '.join(names)} (linear RGB)")
    imgui.pop_id()
    return changed or moved or picked, value


def _path_widget(param: Parameter, current: str) -> tuple[bool, str]:
    """A file name field (applied on Enter) and an "Open..." button; (changed, value)."""
    dialog = _PATH_DIALOGS.setdefault(
        param.name, OpenFileDialog(f"Open {param.name}", param.name, param.choices or ("",))
    )
    imgui.push_id(param.name)
    if imgui.button("Open..."):
        dialog.open()  # NoFileDialogError reaches parameter_widgets' status line
    imgui.same_line()
    changed, value = imgui.input_text(param.name, current, imgui.InputTextFlags_.enter_returns_true)
    imgui.pop_id()
    chosen = dialog.poll()
    if chosen is not None:
        return True, str(chosen)
    return changed, value


def parameter_widgets(values: ParameterValues, status: StatusLine) -> None:
    """Draw a widget per declared parameter; a clamp is noted, a rejected value is an error."""
    for param in values:
        try:
            note = parameter_widget(values, param)
            if note:
                status.note(note)
        except UserError as exc:  # a rejected value, or no file dialog program
            status.error(str(exc))
