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
from envstudio.plugin import Figure, FigureRequest, Session, tile, write_image

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


def _panel(session: Session, values: dict, size: tuple[int, int]) -> npt.NDArray[np.uint8]:
    method = session.method("kautz")
    method.values.update(values)
    session.render_offscreen(method, size)
    return session.read_ldr()


def render_figure6(session: Session, size: tuple[int, int]) -> npt.NDArray[np.uint8]:
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
    return tile(
        [
            [_panel(session, {"lod_bias": b, "fresnel": f}, size) for f in FIGURE6_FRESNEL]
            for b in FIGURE6_LOD_BIAS
        ]
    )


def render_seam_pair(session: Session, size: tuple[int, int]) -> npt.NDArray[np.uint8]:
    """Seed 000 Figure 4's setting, b = 9.4: box mip chain (left), cross-face chain (right).

    Returns
    -------
    (h, 2w + 2, 3) uint8
        As displayed.
    """
    return tile(
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


def seam_levels(session: Session) -> list[SeamLevel]:
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


def draw_grid(request: FigureRequest) -> list[str]:
    """``envstudio figure kautz-grid``: Figure 6 written to ``request.output``."""
    request.method("kautz", FIGURE6_VALUES)
    write_image(request.output, render_figure6(request.session, request.size))
    rows = ", ".join(map(str, FIGURE6_LOD_BIAS))
    columns = ", ".join(map(str, FIGURE6_FRESNEL))
    return [
        f"{request.output}: rows b = {rows} (top to bottom), "
        f"columns f_λ = {columns} (left to right)"
    ]


def draw_seams(request: FigureRequest) -> list[str]:
    """``envstudio figure kautz-seams``: Figure 4's pair and the seam measurement."""
    request.method("kautz", SEAM_VALUES)
    image = render_seam_pair(request.session, request.size)
    levels = seam_levels(request.session)
    write_image(request.output, image)
    lines = [
        f"{request.output}: b = {SEAM_LOD_BIAS}: box mip chain (left), cross-face (right)",
        "mean step between neighbouring texels, across face edges / inside faces:",
        f"{'level':>5} {'face':>5} {'box across':>11} {'inside':>8} {'ratio':>6}   "
        f"{'cross-face across':>17} {'inside':>8} {'ratio':>6}",
    ]
    for s in levels:
        lines.append(
            f"{s.level:>5} {s.size:>5} {s.box_across:>11.4g} {s.box_inside:>8.4g} "
            f"{s.box_across / s.box_inside:>6.2f}   {s.cross_across:>17.4g} "
            f"{s.cross_inside:>8.4g} {s.cross_across / s.cross_inside:>6.2f}"
        )
    return lines


GRID = Figure(
    "kautz-grid",
    "seed 000 Figure 6 (b x f_lambda)",
    draw_grid,
)
SEAMS = Figure(
    "kautz-seams",
    "seed 000 Figure 4, box vs cross-face mip chain at b = 9.4, with the seam measurement",
    draw_seams,
)
