"""``envstudio bench --methods hwconv --hwconv-accuracy``: hwconv against the brute force.

Seed 004 §5.2 convolves a dual paraboloid with shift-invariant kernels and blends
two of them by d²; this measures what that costs in accuracy against the
brute-force Phong prefilter of the same environment (prefilter.brute_force.phong:
seed 000 eq. 7's normalised lobe (N + 1)/2π ⟨r, l⟩^N over every texel, not clamped
at ε), per exponent and for the three results the method can draw:

    two_pass   the blended map (1 − d²) S + d² L (the paper)
    one_pass   map S alone (the paper's 1-pass column)
    exact      the shift-variant kernel (kernel=exact, past the paper)

Each result is read back from the GPU and looked up bilinearly at unit directions
of a Fibonacci lattice, both faces, as shaders/hwconv/hwconv.glsl looks it up along
the reflection vector (core.resample.sample_paraboloid at the map's own level: the
shrunk S and L keep the face's proportions of disc and border). The brute force
reads the lat-long box-downsampled to prefilter.glossiness.reference_height, which
resolves the lobe. The error is relative per RGB channel, |ours − brute| / brute,
reported as RMS and maximum over every direction and channel.

One border serves every exponent and mode: the largest reach of the exact kernel
beyond the rim (radii.outward_radius at the smallest N), unless ``border`` is wider.
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np
from tqdm import tqdm

from envstudio.core.resample import sample_paraboloid
from envstudio.errors import ParameterError
from envstudio.methods.hwconv.radii import plan_filters
from envstudio.prefilter.brute_force import downsample_latlong, phong
from envstudio.prefilter.glossiness import fibonacci_directions, reference_height
from envstudio.render.session import RenderSession

__all__ = ["MODES", "format_accuracy", "run_accuracy"]

#: Mode → (hwconv values, map read back).
MODES = {
    "two_pass": ({"kernel": "two_maps", "one_pass": False}, "blended"),
    "one_pass": ({"kernel": "two_maps", "one_pass": True}, "small"),
    "exact": ({"kernel": "exact", "one_pass": False}, "exact"),
}
_PAIRS_PER_CALL = 2**25  # directions × source texels per brute-force call


def _brute_force(image: np.ndarray, directions: np.ndarray, exponent: float) -> np.ndarray:
    """(m, 3) float64 brute-force Phong prefilter at ``directions``, chunked."""
    small = downsample_latlong(image, reference_height(exponent, image.shape[0]))
    step = max(1, _PAIRS_PER_CALL // (small.shape[0] * small.shape[1]))
    return np.concatenate(
        [phong(small, directions[i : i + step], exponent) for i in range(0, len(directions), step)]
    )


def run_accuracy(
    session: RenderSession, exponents: list[float], directions: int, progress: bool = True
) -> dict:
    """RMS and maximum relative error of every mode at every exponent.

    Parameters
    ----------
    session
        Session whose ``hwconv`` method keeps the map parameters it was given
        (``map_size``, ``epsilon``, ``max_kernel``); its scene must have no local
        objects (the brute force sees only the environment).
    exponents
        Phong exponents N.
    directions
        Lookup directions (Fibonacci lattice over the whole sphere).

    Returns
    -------
    dict
        JSON-ready: the environment, map, directions and per exponent ``rows`` with
        ``brute_s``, and per mode ``rms``, ``max`` (relative), ``max_at_d`` (the
        worst direction's distance d from its face's centre), ``map_texels`` and
        ``filter_s`` (refilter and read back).
    """
    scene = session.scene
    if scene.local_objects():
        raise ParameterError(
            f"--hwconv-accuracy --scene {scene.name}: expected a scene without local objects "
            "(the brute force filters the environment alone)"
        )
    method = session.method("hwconv")
    values = method.values
    map_size, epsilon = int(values["map_size"]), float(values["epsilon"])
    max_kernel = int(values["max_kernel"])
    plans = [plan_filters(n, epsilon, map_size, 0, max_kernel) for n in exponents]
    need = max(math.ceil(p.required_border(exact=True) - 1e-9) for p in plans)
    values.update({"border": max(int(values["border"]), need), "view": "reflector"})
    values["refilter_every_frame"] = False
    border = int(values["border"])
    face_size = map_size + 2 * border
    image = np.asarray(scene.environment.radiance, dtype=np.float64)
    dirs = fibonacci_directions(directions)
    # d of each direction on its face (core.paraboloid): 0 at the centre, 1 at the rim.
    rim_distance = np.linalg.norm(dirs[:, :2], axis=-1) / (1.0 + np.abs(dirs[:, 2]))
    bar = tqdm(
        total=len(exponents) * (1 + len(MODES)),
        desc="hwconv accuracy",
        disable=not progress,
        file=sys.stderr,
    )
    rows = []
    for exponent in exponents:
        start = time.perf_counter()
        truth = _brute_force(image, dirs, exponent)
        row = {"exponent": float(exponent), "brute_s": time.perf_counter() - start}
        bar.update(1)
        for mode, (mode_values, map_name) in MODES.items():
            values.update({**mode_values, "phong_exponent": float(exponent)})
            start = time.perf_counter()
            session.render_offscreen(method, (8, 8))
            session.ctx.finish()
            maps = method.convolution.maps[map_name].read()
            ours = sample_paraboloid(maps, dirs, border * maps.shape[1] / face_size)
            rel = np.abs(ours - truth) / truth
            row[mode] = {
                "rms": float(np.sqrt(np.mean(rel**2))),
                "max": float(rel.max()),
                "max_at_d": float(rim_distance[np.argmax(rel.max(axis=-1))]),
                "map_texels": int(maps.shape[1]),
                "filter_s": time.perf_counter() - start,
            }
            bar.update(1)
        rows.append(row)
    bar.close()
    return {
        "environment": scene.environment.name,
        "source": f"{image.shape[1]}x{image.shape[0]} lat-long",
        "map": {
            "size": map_size,
            "border": border,
            "epsilon": epsilon,
            "max_kernel": max_kernel,
            "cube": session.gpu_scene.cube_size,
        },
        "directions": int(directions),
        "rows": rows,
    }


def format_accuracy(report: dict) -> str:
    """The table as Markdown: RMS / max relative error per exponent and mode."""
    m = report["map"]
    lines = [
        f"relative error against the brute-force Phong prefilter, {report['environment']} "
        f"({report['source']}), map {m['size']} + 2·{m['border']} from a {m['cube']}² cube, "
        f"ε = {m['epsilon']:g}, maximum kernel {m['max_kernel']}, {report['directions']} "
        "directions: RMS / max (d of the max: 0 the face's centre, 1 the rim)",
        "",
        "| N | 2-pass (two maps) | 1-pass | exact | S texels | brute force s |",
        "| ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for row in report["rows"]:
        cells = [
            f"{row[mode]['rms']:.2%} / {row[mode]['max']:.0%} (d {row[mode]['max_at_d']:.2f})"
            for mode in MODES
        ]
        lines.append(
            f"| {row['exponent']:g} | {' | '.join(cells)} | {row['one_pass']['map_texels']} | "
            f"{row['brute_s']:.1f} |"
        )
    return "\n".join(lines)
