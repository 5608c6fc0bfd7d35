"""Target environment maps of the CPU prefilter: texel directions and the EXR layout.

A target is stored as (faces, rows, columns, 3) with the face layouts of core:
dual paraboloid (2, S, S) with a border of B texels (core.paraboloid), cube
(6, S, S) in OpenGL order (core.cubemap), lat-long (1, S, 2S) (core.latlong).
Every texel is computed from its centre direction, so border texels are exact
values just past the rim, not an extrapolation.

The picture written to EXR is the one ``envstudio envmap`` writes:
paraboloid front | back, each upright; cube as the horizontal cross; lat-long as is.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.core import cubemap, latlong, paraboloid

__all__ = ["PARAMETERIZATIONS", "target_directions", "target_picture", "target_shape"]

PARAMETERIZATIONS = ("paraboloid", "cube", "latlong")


def target_shape(param: str, size: int) -> tuple[int, int, int]:
    """(faces, rows, columns) of a target of face edge (lat-long: height) ``size``."""
    return {"paraboloid": (2, size, size), "cube": (6, size, size), "latlong": (1, size, 2 * size)}[
        param
    ]


def target_directions(param: str, size: int, border: int = 0) -> npt.NDArray[np.float64]:
    """Unit centre directions of every target texel.

    Parameters
    ----------
    param
        One of :data:`PARAMETERIZATIONS`.
    size
        Face edge S in texels (lat-long: the height; the width is 2S).
    border
        Paraboloid border B in texels (ignored for the others).

    Returns
    -------
    (faces, rows, columns, 3) float64
        World-space unit directions, shape :func:`target_shape`.
    """
    if param == "paraboloid":
        return paraboloid.texel_directions(size, border)
    if param == "cube":
        return cubemap.texel_directions(size)
    return latlong.texel_directions(size)[None]


def target_picture(param: str, maps: npt.ArrayLike) -> np.ndarray:
    """Lay a (faces, rows, columns, 3) target out as one picture, row 0 at the top.

    Returns
    -------
    (h, w, 3) array
        Paraboloid: (S, 2S) front | back with rows flipped (t grows upwards), as
        envmap.conversions.save_paraboloid_exr; cube: (3S, 4S) horizontal cross;
        lat-long: (S, 2S).
    """
    maps = np.asarray(maps)
    if param == "paraboloid":
        return np.concatenate([maps[0][::-1], maps[1][::-1]], axis=1)
    if param == "cube":
        return cubemap.faces_to_cross(maps)
    return maps[0]
