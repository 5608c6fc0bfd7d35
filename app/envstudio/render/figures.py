"""Figures of method ``kautz``: seed 000 Figure 6 (the b × f_λ grid) and Figure 4 (seams).

``envstudio figure kautz-grid`` renders Figure 6: rows b = 0, 0.8, 1.7, 2.4 (top
to bottom), columns f_λ = 0.03, 0.09, 0.26, 0.42 (left to right), as the paper
lays it out. ``envstudio figure kautz-seams`` renders Figure 4's setting, b = 9.4,
with the hardware box mip chain (left) and the cross-face chain (right), and
measures the seams of both chains with :func:`envstudio.envmap.mipmaps.edge_jumps`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from envstudio.envmap.conversions import read_cube
from envstudio.envmap.mipmaps import build_cross_face_mipmaps, edge_jumps, mipmapped_cube
from envstudio.render.session import RenderSession

__all__ = [
    "FIGURE6_FRESNEL",
    "FIGURE6_LOD_BIAS",
    "FIGURE6_VALUES",
    "SEAM_LOD_BIAS",
    "SEAM_VALUES",
    "SeamLevel",
    "render_figure6",
    "render_seam_pair",
    "seam_levels",
]

#: Seed 000 Figure 6: b per row (top to bottom) and f_λ per column (left to right).
FIGURE6_LOD_BIAS = (0.0, 0.8, 1.7, 2.4)
FIGURE6_FRESNEL = (0.03, 0.09, 0.26, 0.42)
#: Other parameters of the Figure 6 panels: a diffuse base that f_λ blends to gloss.
FIGURE6_VALUES = {"kd": 0.8}
#: Seed 000 Figure 4: the bias at which the faces show, on a pure glossy reflector.
SEAM_LOD_BIAS = 9.4
SEAM_VALUES = {"kd": 0.0, "fresnel": 1.0}
_GAP = 2  # pixels between panels


def _panel(session: RenderSession, values: dict, size: tuple[int, int]) -> npt.NDArray[np.uint8]:
    method = session.method("kautz")
    method.values.update(values)
    session.render_offscreen(method, size)
    return session.read_ldr()


def _tile(panels: list[list[npt.NDArray[np.uint8]]]) -> npt.NDArray[np.uint8]:
    """Panels (rows of (h, w, 3) images) side by side with white gaps."""
    h, w = panels[0][0].shape[:2]
    rows, cols = len(panels), len(panels[0])
    out = np.full((rows * h + (rows - 1) * _GAP, cols * w + (cols - 1) * _GAP, 3), 255, np.uint8)
    for i, row in enumerate(panels):
        for j, image in enumerate(row):
            out[i * (h + _GAP) : i * (h + _GAP) + h, j * (w + _GAP) : j * (w + _GAP) + w] = image
    return out


def render_figure6(session: RenderSession, size: tuple[int, int]) -> npt.NDArray[np.uint8]:
    """Seed 000 Figure 6 with the session's scene and the method's other parameters.

    Parameters
    ----------
    session
        Session whose ``kautz`` method is used as configured (k_d, SH, …).
    size
        (w, h) of one panel in pixels.

    Returns
    -------
    (4h + 6, 4w + 6, 3) uint8
        As displayed; rows b = 0 … 2.4, columns f_λ = 0.03 … 0.42.
    """
    return _tile(
        [
            [_panel(session, {"lod_bias": b, "fresnel": f}, size) for f in FIGURE6_FRESNEL]
            for b in FIGURE6_LOD_BIAS
        ]
    )


def render_seam_pair(session: RenderSession, size: tuple[int, int]) -> npt.NDArray[np.uint8]:
    """Seed 000 Figure 4's setting, b = 9.4: box mip chain (left), cross-face chain (right).

    Returns
    -------
    (h, 2w + 2, 3) uint8
        As displayed.
    """
    return _tile(
        [
            [
                _panel(session, {"lod_bias": SEAM_LOD_BIAS, "cross_face_filter": on}, size)
                for on in (False, True)
            ]
        ]
    )


@dataclass(frozen=True)
class SeamLevel:
    """Seam measurements of one mip level of both chains.

    Attributes
    ----------
    level, size : int
        Mip level and its face edge in texels.
    box_across, box_inside, cross_across, cross_inside : float
        Mean step between neighbouring texels across the 12 face edges and inside the
        faces (edge_jumps), for the box chain and the cross-face chain.
    """

    level: int
    size: int
    box_across: float
    box_inside: float
    cross_across: float
    cross_inside: float


def seam_levels(session: RenderSession) -> list[SeamLevel]:
    """Edge and interior steps of every level with faces of 2 texels or more.

    The box chain is the session's environment cube map (hardware mips); the
    cross-face chain is rebuilt from its level 0.
    """
    ctx, programs = session.ctx, session.programs
    box = session.gpu_scene.cube
    size = box.size[0]
    cross = mipmapped_cube(ctx, size)
    pixels = ctx.buffer(reserve=size * size * 16)
    try:
        for face in range(6):
            box.read_into(pixels, face)
            cross.write(face, pixels)
        build_cross_face_mipmaps(ctx, programs, cross)
        result = []
        level = 1
        while size >> level >= 2:
            box_across, box_inside = edge_jumps(read_cube(box, level, programs))
            cross_across, cross_inside = edge_jumps(read_cube(cross, level, programs))
            result.append(
                SeamLevel(
                    level,
                    size >> level,
                    float(np.mean(list(box_across.values()))),
                    box_inside,
                    float(np.mean(list(cross_across.values()))),
                    cross_inside,
                )
            )
            level += 1
        return result
    finally:
        pixels.release()
        cross.release()
