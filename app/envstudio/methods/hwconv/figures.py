"""Seed 004 Figure 3 for method ``hwconv``: a paraboloid-space kernel's distortion on the sphere.

``envstudio figure hwconv-distortion`` plots the distortion of a circular kernel
of paraboloid space mapped back to the sphere against its radius and its
distance d from the face's centre (no GL).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from envstudio.io.atomic import atomic_path
from envstudio.methods.hwconv import distortion
from envstudio.methods.hwconv.radii import plan_filters
from envstudio.plugin import Figure, FigureRequest

#: Seed 004 Figure 3: kernel radii r (units of the disc's radius) plotted against d, and
#: the distances d whose projected border the right panel draws (at the largest r).
FIGURE3_RADII = (0.05, 0.1, 0.2, 0.3, 0.4, 0.5)
FIGURE3_DISTANCES = (0.0, 0.25, 0.5, 0.75, 1.0)


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


def draw_distortion(request: FigureRequest) -> list[str]:
    """``envstudio figure hwconv-distortion``: Figure 3 written to ``request.output``."""
    numbers = write_distortion_figure(request.output)
    lines = [
        f"{request.output}: distortion e(r, d) against d for r = "
        f"{', '.join(map(str, FIGURE3_RADII))} (left), border distance over ρ at "
        f"r = {max(FIGURE3_RADII)} (right); largest e {100 * numbers['max_error']:.1f} %"
    ]
    for exponent, (r_l, e) in numbers["table"].items():
        lines.append(f"N = {exponent:>3}: r_l = {r_l:.3f} of the disc's radius, at the rim {e:.1%}")
    return lines


DISTORTION = Figure(
    "hwconv-distortion",
    "seed 004 Figure 3, a paraboloid kernel's distortion on the sphere (no GL; the scene "
    "options are ignored)",
    draw_distortion,
    gl=False,
)
