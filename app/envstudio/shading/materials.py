"""Material parameters more than one method declares: the Banks model's (seed 004 §5.3).

``banks`` renders the model through its 3D map and ``reference`` integrates it
(``model=banks``); both declare these, so a scene's material sets both alike.
"""

from __future__ import annotations

from envstudio.core.parameters import Parameter
from envstudio.scene.tangents import AXES, FIELDS

#: Sharpness, tangent field and axis, and the lobe's normalisation.
BANKS_MATERIAL_PARAMETERS = (
    Parameter(
        "sharpness",
        "float",
        0.9,
        0.0,
        0.9999,
        "s",
        "Banks sharpness s ∈ [0, 1) of seed 004 §5.3: the highlight cone's half-thickness "
        "is acos(s).",
    ),
    Parameter(
        "tangent_field",
        "choice",
        "axis",
        choices=FIELDS,
        help="Tangents: around the axis (brushed, turned), along it, radial from it, or the "
        "mesh's UV u direction (falls back to axis without UVs).",
    ),
    Parameter(
        "tangent_axis",
        "choice",
        "y",
        choices=tuple(AXES),
        help="Axis (or direction) of the tangent field, in mesh coordinates.",
    ),
    Parameter(
        "normalize",
        "bool",
        True,
        help="Divide the lobe by its integral at each ⟨v,t⟩ (a white environment reflects "
        "white); off: the paper's 1/(1 − s)², many times brighter.",
    ),
)
