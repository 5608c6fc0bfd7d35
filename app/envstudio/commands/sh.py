"""``envstudio sh``: SH coefficients and extracted lights of an environment (seed 000 §4.1)."""

from __future__ import annotations

import argparse
import json

from envstudio.commands.common import add_env_width_option
from envstudio.engine.hooks import Command
from envstudio.errors import ParameterError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Environment, order, lights, source resampling, check, JSON."""
    parser.add_argument("--env", required=True, help="lat-long environment (.exr or .hdr)")
    add_env_width_option(parser)
    parser.add_argument(
        "--coefficients",
        type=int,
        choices=(9, 25, 49),
        default=9,
        help="SH order: 9 (eq. 9, default), 25 or 49 (bands with a non-zero cosine term)",
    )
    parser.add_argument(
        "--lights", type=int, default=0, help="extract this many cap lights first (0..32)"
    )
    parser.add_argument(
        "--threshold", type=float, default=1.0, help="light threshold in mean luminances"
    )
    parser.add_argument("--height", type=int, help="box-filter the map to this many rows first")
    parser.add_argument(
        "--cube", type=int, help="project a 6xNxN cube resampled from the map (N = this)"
    )
    parser.add_argument(
        "--check",
        action="store_true",
        help="irradiance error against brute force over the same samples (2000 random normals)",
    )
    parser.add_argument("--json", action="store_true", help="machine-readable output")


def run(args: argparse.Namespace) -> int:
    """``envstudio sh``: SH coefficients and extracted lights of an environment (seed 000 §4.1)."""
    import time

    from envstudio.core import cubemap, latlong
    from envstudio.core.resample import latlong_to_cube
    from envstudio.core.sh_bands import BAND_SETS, band_indices
    from envstudio.core.sh_lights import DiffuseProjector
    from envstudio.io.images import read_environment
    from envstudio.prefilter.brute_force import downsample_latlong

    if not 0 <= args.lights <= 32 or not args.threshold > 0:
        raise ParameterError(
            f"--lights {args.lights} --threshold {args.threshold}: expected 0..32 and > 0"
        )
    if args.cube is not None and not 8 <= args.cube <= 1024:
        raise ParameterError(f"--cube {args.cube}: expected a face size in 8..1024")
    radiance = read_environment(args.env, args.max_env_width)
    if args.height is not None:
        if args.height < 1 or radiance.shape[0] % args.height:
            raise ParameterError(
                f"--height {args.height}: expected a divisor of the map's {radiance.shape[0]} rows"
            )
        radiance = downsample_latlong(radiance, args.height)
    if args.cube:
        samples = latlong_to_cube(radiance, args.cube)
        directions = cubemap.texel_directions(args.cube)
        solid_angles = cubemap.texel_solid_angles(args.cube)
        source = f"6x{args.cube}x{args.cube} cube"
    else:
        samples = radiance
        directions = latlong.texel_directions(*radiance.shape[:2])
        solid_angles = latlong.texel_solid_angles(*radiance.shape[:2])
        source = f"{radiance.shape[1]}x{radiance.shape[0]} lat-long"
    projector = DiffuseProjector(
        directions,
        solid_angles,
        coefficients=args.coefficients,
        lights=args.lights,
        threshold=args.threshold,
    )
    times = []
    for _ in range(5):
        start = time.perf_counter()
        lighting = projector.project(samples)
        times.append((time.perf_counter() - start) * 1e3)
    degree, order = band_indices(BAND_SETS[args.coefficients])
    report = {
        "environment": str(args.env),
        "source": source,
        "order": "seed 000 eq. 9 (bands 0, 1, 2, then the even bands), m = -l..l",
        "l": degree.tolist(),
        "m": order.tolist(),
        "coefficients": lighting.coefficients.tolist(),
        "lights": [
            {"direction": row[:3].tolist(), "sin2_alpha": float(row[3]), "rgb": row[4:].tolist()}
            for row in lighting.lights
        ],
        "projection_ms": min(times),
    }
    if args.check:
        report["check"] = _irradiance_check(samples, directions, solid_angles, lighting)
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    residual = f" of the residual after {len(lighting.lights)} lights" if args.lights else ""
    print(f"{args.env}: {source} projected in {min(times):.2f} ms (best of 5); L_i{residual}")
    print(f"{'i':>3} {'Y_i':<7} {'l':>2} {'m':>3} {'R':>12} {'G':>12} {'B':>12}")
    for i, rgb in enumerate(lighting.coefficients):
        name = _SH9_NAMES[i] if i < len(_SH9_NAMES) else ""
        values = " ".join(f"{v:>12.6g}" for v in rgb)
        print(f"{i:>3} {name:<7} {degree[i]:>2} {order[i]:>3} {values}")
    for k, light in enumerate(report["lights"]):
        d = ", ".join(f"{v:+.4f}" for v in light["direction"])
        rgb = " ".join(f"{v:.6g}" for v in light["rgb"])
        print(f"light {k:>2}: direction ({d}) sin²α {light['sin2_alpha']:.3g} moment {rgb}")
    if args.check:
        check = report["check"]
        print(
            f"irradiance vs brute force over the same {source} ({check['normals']} random "
            f"normals, luminance): mean {check['mean_relative_error'] * 100:.2f} %, "
            f"max {check['max_relative_error'] * 100:.2f} %"
        )
    return 0


# The basis functions of seed 000 eq. 9, by index.
_SH9_NAMES = ("1", "y", "z", "x", "xy", "yz", "3z²-1", "xz", "x²-y²")


def _irradiance_check(radiance, directions, solid_angles, lighting, normals: int = 2000) -> dict:
    """Relative error (luminance) of ``lighting``'s irradiance against the brute-force sum
    Σ_k L_k max(n·d_k, 0) Δω_k over the samples it was projected from."""
    import numpy as np

    from envstudio.core.env_sampling import luminance

    n = np.random.default_rng(0).normal(size=(normals, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    weighted = luminance(radiance).reshape(-1) * np.asarray(solid_angles).reshape(-1)
    truth = np.concatenate(
        [np.maximum(n[i : i + 16] @ d.T, 0.0) @ weighted for i in range(0, normals, 16)]
    )
    error = np.abs(luminance(lighting.irradiance(n)) - truth) / truth
    return {
        "normals": normals,
        "mean_relative_error": float(error.mean()),
        "max_relative_error": float(error.max()),
    }


COMMAND = Command("sh", "SH coefficients of an environment (seed 000 eq. 9-11)", run, add_arguments)
