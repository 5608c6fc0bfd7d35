"""f_λ presets: the reflectance at normal incidence of common conductors and dielectrics.

Seed 000 §5.2 defines f_λ as "the color of reflected white light at normal incidence"; a
method's ``fresnel`` parameter (a ``color``) takes these names as well as numbers
(``--param fresnel=gold``, the panel's preset menu, ``fresnel = "gold"`` in a scene file).

Source, every row: N. Hoffman, "Background: Physically-Based Shading", in *Physically-Based
Shading Models in Film and Game Production*, SIGGRAPH 2010 course notes, Table 1 "Values of
F(0°) for various materials", the **linear** column as printed (the table is Real-Time
Rendering 3rd ed., Table 7.3, reproduced there with A K Peters' permission). Hoffman's
SIGGRAPH 2015 "Physics and Math of Shading" notes give the same metals. The values are linear
RGB reflectances, used here as they are in Schlick's F = f_λ + (1 − f_λ)(1 − cos θ)^5 per
channel; they are not converted from the sRGB column.
"""

from __future__ import annotations

from dataclasses import dataclass

from envstudio.core.parameters import Parameter


@dataclass(frozen=True)
class FresnelPreset:
    """One row: a name, its linear-RGB F(0°) and the table row it is copied from."""

    name: str
    f0: tuple[float, float, float]
    row: str


_TABLE = "Hoffman 2010, Table 1 (RTR3 Table 7.3), linear F(0°)"

#: The presets, in the panel's order (conductors, then dielectrics).
FRESNEL_PRESETS: tuple[FresnelPreset, ...] = (
    FresnelPreset("gold", (1.00, 0.71, 0.29), f"{_TABLE}: Gold"),
    FresnelPreset("silver", (0.95, 0.93, 0.88), f"{_TABLE}: Silver"),
    FresnelPreset("copper", (0.95, 0.64, 0.54), f"{_TABLE}: Copper"),
    FresnelPreset("aluminium", (0.91, 0.92, 0.92), f"{_TABLE}: Aluminum"),
    FresnelPreset("iron", (0.56, 0.57, 0.58), f"{_TABLE}: Iron"),
    FresnelPreset("diamond", (0.17, 0.17, 0.17), f"{_TABLE}: Diamond"),
    FresnelPreset("plastic", (0.05, 0.05, 0.05), f"{_TABLE}: Plastic High"),
    FresnelPreset("glass", (0.03, 0.03, 0.03), f"{_TABLE}: Plastic / Glass (Low)"),
    FresnelPreset("water", (0.02, 0.02, 0.02), f"{_TABLE}: Water"),
)

#: Name → linear RGB F(0°), as :class:`~envstudio.core.parameters.Parameter` takes presets.
FRESNEL_RGB: dict[str, tuple[float, float, float]] = {p.name: p.f0 for p in FRESNEL_PRESETS}


def fresnel_parameter(default: float = 1.0, help: str = "", **extra) -> Parameter:
    """The shared ``fresnel`` (f_λ): linear RGB in [0, 1] with :data:`FRESNEL_PRESETS`.

    ``default`` is a grey; ``extra`` goes to :class:`Parameter` (``applies_when``, ...).
    """
    text = help or "Schlick reflectance at normal incidence, per RGB channel (1 = mirror)."
    return Parameter(
        "fresnel", "color", (default,) * 3, 0.0, 1.0, "f_λ", text, presets=FRESNEL_RGB, **extra
    )


def kd_parameter(default: float = 0.0, help: str = "", **extra) -> Parameter:
    """The shared ``kd`` (k_d): a linear-RGB diffuse albedo in [0, 1], ``default`` grey."""
    text = help or "Diffuse albedo, per RGB channel."
    return Parameter("kd", "color", (default,) * 3, 0.0, 1.0, "k_d", text, **extra)
