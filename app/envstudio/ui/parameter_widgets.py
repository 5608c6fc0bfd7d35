"""ImGui widgets built from parameter declarations, holding no copy of the state.

Each widget reads the current value from a :class:`ParameterValues` and, when
the user changes it, assigns it back (``values[name] = v``), where the
declaration validates it::

    float   slider_float over [minimum, maximum], logarithmic when ``log``
    int     slider_int over [minimum, maximum]
    bool    checkbox
    choice  combo of ``choices``

The unit and help text form the tooltip.
"""

from __future__ import annotations

from imgui_bundle import imgui

from envstudio.errors import ParameterError
from envstudio.methods.parameters import Parameter, ParameterValues
from envstudio.ui.status import StatusLine

_CLAMP = imgui.SliderFlags_.always_clamp


def tooltip(param: Parameter) -> str:
    """Help text followed by the unit, e.g. ``"Schlick reflectance ... [f_λ]"``."""
    unit = f" [{param.unit}]" if param.unit else ""
    return f"{param.help}{unit}".strip()


def parameter_widget(values: ParameterValues, param: Parameter) -> bool:
    """Draw the widget of ``param``; returns True if the user changed its value.

    Raises
    ------
    ParameterError
        If the declaration rejects the value the widget produced.
    """
    label = param.name
    current = values[param.name]
    if param.kind == "float":
        flags = _CLAMP | (imgui.SliderFlags_.logarithmic if param.log else 0)
        changed, value = imgui.slider_float(
            label, float(current), float(param.minimum), float(param.maximum), "%.3f", flags
        )
    elif param.kind == "int":
        changed, value = imgui.slider_int(
            label, int(current), int(param.minimum), int(param.maximum), "%d", _CLAMP
        )
    elif param.kind == "bool":
        changed, value = imgui.checkbox(label, bool(current))
    else:
        index = param.choices.index(current)
        changed, index = imgui.combo(label, index, list(param.choices))
        value = param.choices[index]
    text = tooltip(param)
    if text:
        imgui.set_item_tooltip(text)
    if changed:
        values[param.name] = value
    return changed


def parameter_widgets(values: ParameterValues, status: StatusLine) -> bool:
    """Draw a widget per declared parameter; a rejected value goes to ``status``.

    Returns
    -------
    bool
        Whether any value changed.
    """
    changed = False
    for param in values:
        try:
            changed |= parameter_widget(values, param)
        except ParameterError as exc:
            status.error(str(exc))
    return changed
