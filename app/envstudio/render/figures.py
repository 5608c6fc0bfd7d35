"""Figures of method ``kautz``: seed 000 Figure 6 (the b × f_λ grid) and Figure 4 (seams).

``envstudio figure kautz-grid`` renders Figure 6: rows b = 0, 0.8, 1.7, 2.4 (top
to bottom), columns f_λ = 0.03, 0.09, 0.26, 0.42 (left to right), as the paper
lays it out. ``envstudio figure kautz-seams`` renders Figure 4's setting, b = 9.4,
with the hardware box mip chain (left) and the cross-face chain (right), and
measures the seams of both chains with :func:`envstudio.envmap.mipmaps.edge_jumps`.
``envstudio figure hwconv-distortion`` plots seed 004 Figure 3 (method ``hwconv``):
the distortion of a paraboloid-space kernel mapped back to the sphere, no GL.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from envstudio.envmap.conversions import read_cube
from envstudio.envmap.mipmaps import build_cross_face_mipmaps, edge_jumps, mipmapped_cube
from envstudio.io.atomic import atomic_path
from envstudio.methods.hwconv import distortion
from envstudio.methods.hwconv.radii import plan_filters
from envstudio.render.session import RenderSession

__all__ = [
    "FIGURE3_DISTANCES",
    "FIGURE3_RADII",
    "FIGURE6_FRESNEL",
    "FIGURE6_LOD_BIAS",
    "FIGURE6_VALUES",
    "SEAM_LOD_BIAS",
    "SEAM_VALUES",
    "SeamLevel",
    "render_figure6",
    "render_seam_pair",
    "seam_levels",
    "write_distortion_figure",
]

#: Seed 000 Figure 6: b per row (top to bottom) and f_λ per column (left to right).
FIGURE6_LOD_BIAS = (0.0, 0.8, 1.7, 2.4)
FIGURE6_FRESNEL = (0.03, 0.09, 0.26, 0.42)
#: Other parameters of the Figure 6 panels: a diffuse base that f_λ blends to gloss.
FIGURE6_VALUES = {"kd": 0.8}
#: Seed 000 Figure 4: the bias at which the faces show, on a pure glossy reflector.
SEAM_LOD_BIAS = 9.4
SEAM_VALUES = {"kd": 0.0, "fresnel": 1.0}
#: Seed 004 Figure 3: kernel radii r (units of the disc's radius) plotted against d, and
#: the distances d whose projected border the right panel draws (at the largest r).
FIGURE3_RADII = (0.05, 0.1, 0.2, 0.3, 0.4, 0.5)
FIGURE3_DISTANCES = (0.0, 0.25, 0.5, 0.75, 1.0)
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


def write_distortion_figure(path: str | os.PathLike, samples: int = 720) -> dict:
    """Seed 004 Figure 3 as a PNG, written atomically; returns the numbers plotted.

    Left: the error e(r, d) of :func:`envstudio.methods.hwconv.distortion.kernel_distortion`
    in percent against d from the face's centre (0) to the rim (1), one curve per radius
    of :data:`FIGURE3_RADII`, with the large kernels r_l of §5.2's table (512-texel
    disc, ε = 0.1) at the rim, where map L carries the whole weight. Right: the
    projected border's distance from the kernel's centre over ρ against the azimuth
    about it (0: towards the rim), r = max(FIGURE3_RADII), one curve per d of
    :data:`FIGURE3_DISTANCES`; a constant radius would be the unit circle.

    Parameters
    ----------
    path
        Output PNG; its folder must exist.
    samples
        Border points per kernel.

    Returns
    -------
    dict
        ``distances`` (the d grid), ``error`` (radius → e per d), ``max_error`` (the
        largest e in the figure), ``table`` (exponent → r_l and e(r_l, 1)).
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    d = np.linspace(0.0, 1.0, 101)
    error = {r: [distortion.kernel_distortion(r, x, samples) for x in d] for r in FIGURE3_RADII}
    table = {}
    for exponent in (10, 50, 100, 250, 500):
        r_l = plan_filters(exponent, 0.1, 512, 64).radius_large / 256.0
        table[exponent] = (r_l, distortion.kernel_distortion(r_l, 1.0, samples))
    fig = plt.figure(figsize=(10, 4.4), dpi=120)
    left = fig.add_subplot(1, 2, 1)
    for r, e in error.items():
        left.plot(d, 100.0 * np.asarray(e), label=f"r = {r:g}")
    left.plot(
        [1.0] * len(table),
        [100.0 * e for _, e in table.values()],
        "k.",
        label="r_l of §5.2's table at the rim",
    )
    for exponent, (_, e) in table.items():
        left.annotate(
            f"N = {exponent}", (1.0, 100.0 * e), textcoords="offset points", xytext=(-44, 2)
        )
    left.set_xlabel("d: distance of the kernel's centre from the paraboloid's centre")
    left.set_ylabel("distortion e (%): max |α − ρ| / ρ")
    left.set_xlim(0.0, 1.05)
    left.set_ylim(bottom=0.0)
    left.grid(True, alpha=0.3)
    left.legend(loc="upper left", fontsize="small")
    right = fig.add_subplot(1, 2, 2, projection="polar")
    r_max = max(FIGURE3_RADII)
    psi = np.linspace(0.0, 2.0 * np.pi, 200)
    right.plot(psi, np.ones_like(psi), "k:", lw=1, label="constant radius")
    for x in FIGURE3_DISTANCES:
        alpha, azimuth = distortion.border_distances(r_max, x, samples)
        order = np.argsort(azimuth)
        rho = 0.5 * (alpha.max() + alpha.min())
        right.plot(
            np.append(azimuth[order], azimuth[order][0]),
            np.append(alpha[order], alpha[order][0]) / rho,
            label=f"d = {x:g}",
        )
    right.set_rmax(1.3)
    right.set_rticks([0.5, 1.0])
    right.set_rlabel_position(100)
    right.set_title(f"border distance / ρ about the kernel's centre, r = {r_max:g}", fontsize=9)
    right.legend(loc="lower left", bbox_to_anchor=(0.95, 0.0), fontsize="small")
    fig.suptitle("Seed 004 Figure 3: a paraboloid-space circle projected back to the sphere")
    fig.tight_layout()
    with atomic_path(Path(path)) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
    return {
        "distances": d.tolist(),
        "error": {r: [float(v) for v in e] for r, e in error.items()},
        "max_error": float(max(max(e) for e in error.values())),
        "table": table,
    }
