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

from envstudio.core.images import GAP
from envstudio.envmap.conversions import read_texture
from envstudio.plugin import Figure, FigureRequest, to_ldr, upright, write_image

__all__ = ["Figure4", "figure4", "figure_image"]


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
        warped.append(read_texture(method.generator.accumulation)[..., :3].copy())
    generated = read_texture(method.generate(frame_d))[..., :3].copy()
    indices, weights = method.generator.sources
    sources = [np.asarray(method.bake.maps[i], dtype=np.float32) for i in indices]
    return Figure4(np.asarray(indices), np.asarray(weights), sources, warped, generated)


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
    out = np.full((2 * n + GAP, 4 * n + 3 * GAP, 3), 255, np.uint8)
    for i, row in enumerate(rows):
        for j, image in enumerate(row):
            if image is not None:
                y, x = i * (n + GAP), j * (n + GAP)
                out[y : y + n, x : x + n] = upright(to_ldr(image, exposure, tonemap), scale)
    return out


def draw_warp(request: FigureRequest) -> list[str]:
    """``envstudio figure rsibr-warp``: Figure 4 of the camera's view, to ``request.output``."""
    method = request.method("rsibr")
    request.session.render_offscreen(method, request.size)
    figure = figure4(method, method.last_frame_d)
    n = figure.generated.shape[0]
    display = request.session.renderer.display
    image = figure_image(
        figure,
        float(display["exposure"]),
        str(display["tonemap"]),
        scale=max(1, request.size[1] // n),
    )
    write_image(request.output, image)
    weights = ", ".join(
        f"view {i} w = {w:.4f}" for i, w in zip(figure.indices, figure.weights, strict=True)
    )
    return [
        f"{request.output}: top: source maps ({weights}); bottom: each warped into the "
        f"camera's frame (times its singularity fade), then the generated map ({n}²)"
    ]


WARP = Figure(
    "rsibr-warp",
    "seed 002 Figure 4, the three source maps, their warps into the camera's frame and the "
    "generated map",
    draw_warp,
)
