"""Colour ramp for error heat maps (twin of shaders/common/colormap.glsl)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

#: Six stops of matplotlib's "magma", linearly interpolated (t = 0, 0.2, ..., 1).
MAGMA_STOPS = np.array(
    [
        [0.001, 0.000, 0.014],
        [0.231, 0.059, 0.439],
        [0.550, 0.161, 0.506],
        [0.868, 0.288, 0.409],
        [0.994, 0.624, 0.427],
        [0.987, 0.991, 0.750],
    ]
)


def magma(t: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Map values (...) in [0, 1] (clamped) to (..., 3) display RGB in [0, 1]."""
    x = np.clip(np.asarray(t, dtype=np.float64), 0.0, 1.0) * (len(MAGMA_STOPS) - 1)
    i = np.minimum(x.astype(int), len(MAGMA_STOPS) - 2)
    f = (x - i)[..., None]
    return MAGMA_STOPS[i] * (1 - f) + MAGMA_STOPS[i + 1] * f
