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

``write_error_images`` lays the same per-direction errors out as pictures, one PNG
per exponent: a row per mode, the front face (z ≥ 0) left and the back face right,
both in their (s, t) = (x, y)/(1 ± z) axes with +Y up, each pixel showing the
error of its nearest lattice direction (so the pictures' maximum is the table's),
the largest of the three channels, through core.colormap.magma over a fixed scale
(saturating above it), with a colour bar.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from envstudio.core.colormap import magma
from envstudio.core.paraboloid import texel_directions
from envstudio.core.resample import sample_paraboloid
from envstudio.methods.hwconv.radii import plan_filters
from envstudio.plugin import ParameterError, Session, write_image
from envstudio.prefilter.brute_force import downsample_latlong, phong
from envstudio.prefilter.glossiness import fibonacci_directions, reference_height

__all__ = [
    "IMAGE_FACE",
    "MODES",
    "error_image_panels",
    "format_accuracy",
    "format_error_images",
    "run_accuracy",
    "write_error_images",
]

#: Mode → (hwconv values, map read back).
MODES = {
    "two_pass": ({"kernel": "two_maps", "one_pass": False}, "blended"),
    "one_pass": ({"kernel": "two_maps", "one_pass": True}, "small"),
    "exact": ({"kernel": "exact", "one_pass": False}, "exact"),
}
_PAIRS_PER_CALL = 2**25  # directions × source texels per brute-force call
#: Mode → its row label in the error images.
_LABELS = {"two_pass": "2-pass", "one_pass": "1-pass", "exact": "exact"}
#: Texels across each face's disc in the error images.
IMAGE_FACE = 128
_LABEL_W, _GAP, _TITLE_H, _BAR_H, _TICKS_H = 64, 4, 22, 12, 20


def _brute_force(image: np.ndarray, directions: np.ndarray, exponent: float) -> np.ndarray:
    """(m, 3) float64 brute-force Phong prefilter at ``directions``, chunked."""
    small = downsample_latlong(image, reference_height(exponent, image.shape[0]))
    step = max(1, _PAIRS_PER_CALL // (small.shape[0] * small.shape[1]))
    return np.concatenate(
        [phong(small, directions[i : i + step], exponent) for i in range(0, len(directions), step)]
    )


def run_accuracy(
    session: Session,
    exponents: list[float],
    directions: int,
    progress: bool = True,
    errors: dict | None = None,
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
    errors
        If given, filled with (exponent, mode) → (directions,) float32, each
        direction's relative error (the largest channel's), for ``write_error_images``.

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
            if errors is not None:
                errors[(float(exponent), mode)] = rel.max(axis=-1).astype(np.float32)
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


def error_image_panels(face: int = IMAGE_FACE) -> dict[str, tuple[int, int, int]]:
    """Mode → (row, column, size) of its front face's square in an error image; the back
    face lies ``face + 4`` columns further right. The disc fills the square."""
    return {mode: (_TITLE_H + k * (face + _GAP), _LABEL_W, face) for k, mode in enumerate(MODES)}


def _nearest_direction(face: int, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(2, face, face) index of the nearest of ``dirs`` for each texel, +Y up, and the disc."""
    texels = texel_directions(face)[:, ::-1]  # row 0 at the top: t = +1
    c = (np.arange(face) + 0.5) / face * 2.0 - 1.0
    inside = (c[None, :] ** 2 + c[::-1, None] ** 2) <= 1.0
    flat = texels.reshape(-1, 3).astype(np.float32)
    lattice = dirs.astype(np.float32).T
    step = max(1, 2**24 // dirs.shape[0])
    nearest = np.concatenate(
        [np.argmax(flat[i : i + step] @ lattice, axis=-1) for i in range(0, len(flat), step)]
    )
    return nearest.reshape(2, face, face), inside


def _text(pixels: np.ndarray, x: int, y: int, text: str, size: int = 13) -> np.ndarray:
    """``pixels`` with black ``text`` drawn at baseline (x, y) (OpenImageIO's own font)."""
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(np.ascontiguousarray(pixels, dtype=np.float32))
    oiio.ImageBufAlgo.render_text(buf, x, y, text, size, "", [0.0, 0.0, 0.0])
    return np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32).reshape(pixels.shape)


def write_error_images(
    report: dict,
    errors: dict,
    json_out: Path | str,
    scale: float = 1.0,
    face: int = IMAGE_FACE,
) -> list[Path]:
    """One PNG per exponent beside ``json_out``: ``STEM.error_N<N>.png``.

    Rows 2-pass, 1-pass, exact; in each the front face left, the back face right
    (``error_image_panels``), each texel the relative error of its nearest lattice
    direction through ``magma(error / scale)``, clamped above ``scale``; outside the
    discs white; a colour bar from 0 to ``scale`` at the bottom. Written atomically.
    """
    json_out = Path(json_out)
    dirs = fibonacci_directions(int(report["directions"]))
    nearest, inside = _nearest_direction(face, dirs)
    panels = error_image_panels(face)
    width = _LABEL_W + 2 * face + 2 * _GAP
    bar_top = _TITLE_H + len(MODES) * (face + _GAP) + _GAP
    height = bar_top + _BAR_H + _TICKS_H
    bar_w = 2 * face + _GAP
    paths = []
    for row in report["rows"]:
        n = row["exponent"]
        pixels = np.ones((height, width, 3), np.float32)
        for mode, (top, left, size) in panels.items():
            err = errors[(float(n), mode)]
            for f in range(2):
                x0 = left + f * (size + _GAP)
                rgb = magma(err[nearest[f]] / scale)
                pixels[top : top + size, x0 : x0 + size][inside] = rgb[inside]
        pixels[bar_top : bar_top + _BAR_H, _LABEL_W : _LABEL_W + bar_w] = magma(
            (np.arange(bar_w) + 0.5) / bar_w
        )[None]
        for mode, (top, _, size) in panels.items():
            pixels = _text(pixels, 4, top + size // 2 + 5, _LABELS[mode])
        title = f"N = {n:g}: relative error, front | back"
        pixels = _text(pixels, _LABEL_W, 16, title)
        ticks_y = bar_top + _BAR_H + 15
        pixels = _text(pixels, _LABEL_W, ticks_y, "0")
        pixels = _text(pixels, _LABEL_W + bar_w // 2 - 12, ticks_y, f"{scale / 2:.0%}")
        pixels = _text(pixels, _LABEL_W + bar_w - 44, ticks_y, f"{scale:.0%}+")
        paths.append(write_image(json_out.with_name(f"{json_out.stem}.error_N{n:g}.png"), pixels))
    return paths


def format_error_images(paths: list[Path], scale: float) -> str:
    """The printout's line listing the error images and their colour scale."""
    return (
        f"error images (magma over 0–{scale:.0%} relative error, saturating above; rows 2-pass, "
        f"1-pass, exact; front | back face): {', '.join(str(p) for p in paths)}"
    )
