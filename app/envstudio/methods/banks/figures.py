"""Seed 004 Figure 6 for method ``banks``: a reflector and three slices of its 3D map.

``envstudio figure banks-slices`` renders, left to right, the scene's reflector with
the anisotropic map (s = 0.99, as the paper's teapot), then slices of
L_banks(t, ⟨v,t⟩) at ∠(v, t) = 44°, 39° and 35° (the paper's right-hand images):
the front paraboloid face of tangents t (methods/banks/maps.py), each pixel the
environment integrated over the cone of directions at 180° − ∠(v, t) from t.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.plugin import Figure, FigureRequest, Method, Session, tile, write_image

#: Seed 004 Figure 6: ∠(v, t) of the slices, degrees, left to right.
SLICE_ANGLES = (44.0, 39.0, 35.0)
#: The paper's sharpness and a brushed reflector around the vertical axis, pure gloss.
FIGURE6_VALUES = {"sharpness": 0.99, "tangent_field": "axis", "tangent_axis": "y", "kd": 0.0}


def render_slices(session: Session, method: Method, size: tuple[int, int]) -> npt.NDArray[np.uint8]:
    """The reflector, then the slices at :data:`SLICE_ANGLES`, as displayed.

    Parameters
    ----------
    session
        Session whose scene is shown.
    method
        Its ``banks`` method, configured (s, tangent field, resolution).
    size
        (w, h) of one panel in pixels.

    Returns
    -------
    (h, 4w + 6, 3) uint8
    """
    panels = []
    for view, angle in (("reflector", 0.0), *(("slice", a) for a in SLICE_ANGLES)):
        method.values.update({"view": view, "slice_angle": angle})
        session.render_offscreen(method, size)
        panels.append(session.read_ldr())
    method.values["view"] = "reflector"
    return tile([panels])


def draw_slices(request: FigureRequest) -> list[str]:
    """``envstudio figure banks-slices``: Figure 6 written to ``request.output``."""
    method = request.method("banks", FIGURE6_VALUES)
    image = render_slices(request.session, method, request.size)
    angles = ", ".join(f"{a:g}°" for a in SLICE_ANGLES)
    write_image(request.output, image)
    return [
        f"{request.output}: s = {method.values['sharpness']:g}: reflector, slices at "
        f"∠(v,t) = {angles}"
    ]


SLICES = Figure(
    "banks-slices",
    "seed 004 Figure 6: the reflector with the Banks map at s = 0.99 and slices of the 3D "
    "map at three angles between v and t",
    draw_slices,
)
