"""Seed 002 Figure 4, live and headless: three source maps, their warps, the generated map.

For the destination frame T_d of the last frame drawn, the face of the view
triangle that holds v_d gives three source maps and their spherical barycentric
weights (§3.4). Each source is warped into T_d alone (§3.3, methods.rsibr.generator,
``only=``), shown as the accumulation holds it: the warped radiance times its
singularity fade. The generated map is the weighted, normalised blend of the three
(§4), the map the reflector is drawn with.

The same images feed the Method panel (:meth:`RsibrMethod.panel_images`) and
``envstudio figure rsibr-warp`` (:func:`figure_image`): two rows, the sources over
their warped versions, the generated map at the end of the second row. Images are
tone mapped as the display does (exposure, shaders/common/tonemap.glsl, sRGB).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from envstudio.envmap.conversions import read_texture

__all__ = ["Figure4", "figure4", "figure_image", "to_ldr"]

_GAP = 2  # pixels between panels, white


@dataclass
class Figure4:
    """The seven maps of Figure 4, linear, in core.spheremap layout (row 0 is t = 0).

    Attributes
    ----------
    indices : (3,) int
        Views of the face holding v_d.
    weights : (3,) float
        Their spherical barycentric weights (sum 1).
    sources : list of (n, n, 3) float32
        The baked maps of those views.
    warped : list of (n, n, 3) float32
        Each warped into T_d alone, times its singularity fade.
    generated : (n, n, 3) float32
        The blend, the map the reflector is drawn with.
    """

    indices: npt.NDArray[np.int64]
    weights: npt.NDArray[np.float64]
    sources: list[npt.NDArray[np.float32]]
    warped: list[npt.NDArray[np.float32]]
    generated: npt.NDArray[np.float32]


def figure4(method, frame_d: npt.ArrayLike) -> Figure4:
    """Figure 4's maps of ``method``'s current bake for destination frame ``frame_d``.

    Parameters
    ----------
    method : RsibrMethod
        A method with a bake (it has drawn a frame).
    frame_d : (3, 3) float
        Destination frame T_d (columns x, y, z of the camera in world space).

    Returns
    -------
    Figure4
        The generator's map is left as the full blend for ``frame_d``.
    """
    warped = []
    for position in range(3):
        method.generate(frame_d, only=position)
        warped.append(read_texture(method._generator.accumulation)[..., :3].copy())
    generated = read_texture(method.generate(frame_d))[..., :3].copy()
    indices, weights = method._generator.sources
    sources = [np.asarray(method.bake.maps[i], dtype=np.float32) for i in indices]
    return Figure4(np.asarray(indices), np.asarray(weights), sources, warped, generated)


def to_ldr(image: npt.ArrayLike, exposure: float = 0.0, tonemap: str = "aces") -> np.ndarray:
    """Linear radiance as displayed: exposure, the tone map, sRGB, 8 bits.

    Parameters
    ----------
    image : (..., 3) float
        Linear radiance.
    exposure
        Stops.
    tonemap
        ``none``, ``reinhard`` or ``aces`` (shaders/common/tonemap.glsl's curves).

    Returns
    -------
    (..., 3) uint8
    """
    c = np.asarray(image, dtype=np.float64) * 2.0**exposure
    if tonemap == "reinhard":
        c = c / (1.0 + c)
    elif tonemap == "aces":
        c = (c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14)
    c = np.clip(c, 0.0, 1.0)
    c = np.where(c < 0.0031308, 12.92 * c, 1.055 * c ** (1.0 / 2.4) - 0.055)
    return np.round(255.0 * np.clip(c, 0.0, 1.0)).astype(np.uint8)


def upright(image: npt.ArrayLike, scale: int = 1) -> np.ndarray:
    """A sphere map turned upright (row 0 at the top), each texel ``scale`` pixels wide."""
    image = np.asarray(image)[::-1]
    return np.repeat(np.repeat(image, scale, axis=0), scale, axis=1)


def figure_image(
    figure: Figure4, exposure: float = 0.0, tonemap: str = "aces", scale: int = 1
) -> np.ndarray:
    """The figure as one image: sources (top row), warped and generated (bottom row).

    Parameters
    ----------
    figure
        From :func:`figure4`.
    exposure, tonemap
        Display settings (:func:`to_ldr`).
    scale
        Pixels per texel.

    Returns
    -------
    (2 h + 2, 4 w + 6, 3) uint8
        h = w = n · scale; the top row's fourth slot is white. Panel (row, column)
        starts at ((h + 2) row, (w + 2) column).
    """
    rows = [[*figure.sources, None], [*figure.warped, figure.generated]]
    n = figure.generated.shape[0] * scale
    out = np.full((2 * n + _GAP, 4 * n + 3 * _GAP, 3), 255, np.uint8)
    for i, row in enumerate(rows):
        for j, image in enumerate(row):
            if image is not None:
                y, x = i * (n + _GAP), j * (n + _GAP)
                out[y : y + n, x : x + n] = upright(to_ldr(image, exposure, tonemap), scale)
    return out
