"""Display settings shared by window, ``render`` and ``compare``: exposure, tone map, background."""

from __future__ import annotations

from envstudio.core.parameters import Parameter, ParameterValues

TONEMAPS = ("none", "reinhard", "aces")

DISPLAY_PARAMETERS = (
    Parameter(
        "exposure",
        "float",
        0.0,
        -10.0,
        10.0,
        "EV",
        "Exposure in stops applied before the tone map (PNG/screen only; EXR stays linear).",
    ),
    Parameter(
        "tonemap",
        "choice",
        "aces",
        choices=TONEMAPS,
        help="Tone mapper between exposure and sRGB encoding.",
    ),
    Parameter("background", "bool", True, help="Draw the environment behind the objects."),
)

#: Their names: ``--param`` takes them for every method.
DISPLAY_NAMES = tuple(p.name for p in DISPLAY_PARAMETERS)


def display_values() -> ParameterValues:
    """Fresh display settings with their defaults."""
    return ParameterValues(DISPLAY_PARAMETERS)
