"""Images as displayed, on the CPU: the display transform and figure panels laid out.

Figures and panels of any method use these, so a figure's PNG looks as the
screen does (exposure, shaders/common/tonemap.glsl's curves, sRGB).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

#: Pixels between a figure's panels (white).
GAP = 2


def displayed(image: npt.ArrayLike, exposure: float = 0.0, tonemap: str = "aces") -> np.ndarray:
    """Linear radiance as displayed, unquantised: exposure, the tone map, sRGB encoding.

    The CPU twin of shaders/frame/display.glsl (and common/tonemap.glsl's curves).

    Parameters
    ----------
    image : (..., 3) float
        Linear radiance.
    exposure
        Stops.
    tonemap
        ``none``, ``reinhard`` or ``aces``.

    Returns
    -------
    (..., 3) float64
        Display values in [0, 1].
    """
    c = np.asarray(image, dtype=np.float64) * 2.0**exposure
    if tonemap == "reinhard":
        c = c / (1.0 + c)
    elif tonemap == "aces":
        c = (c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14)
    c = np.clip(c, 0.0, 1.0)
    return np.where(c < 0.0031308, 12.92 * c, 1.055 * c ** (1.0 / 2.4) - 0.055)


def to_ldr(image: npt.ArrayLike, exposure: float = 0.0, tonemap: str = "aces") -> np.ndarray:
    """Linear radiance as displayed (:func:`displayed`) in 8 bits: (..., 3) uint8."""
    return np.round(255.0 * displayed(image, exposure, tonemap)).astype(np.uint8)


def upright(image: npt.ArrayLike, scale: int = 1) -> np.ndarray:
    """A sphere map turned upright (row 0 at the top), each texel ``scale`` pixels wide."""
    image = np.asarray(image)[::-1]
    return np.repeat(np.repeat(image, scale, axis=0), scale, axis=1)


def tile(panels: list[list[npt.NDArray[np.uint8]]]) -> npt.NDArray[np.uint8]:
    """Panels (rows of (h, w, 3) images) side by side with white gaps."""
    h, w = panels[0][0].shape[:2]
    rows, cols = len(panels), len(panels[0])
    out = np.full((rows * h + (rows - 1) * GAP, cols * w + (cols - 1) * GAP, 3), 255, np.uint8)
    for i, row in enumerate(panels):
        for j, image in enumerate(row):
            out[i * (h + GAP) : i * (h + GAP) + h, j * (w + GAP) : j * (w + GAP) + w] = image
    return out
