"""``envstudio compare``: methods against the converged ground truth, images and a table."""

from __future__ import annotations

import argparse
import sys

from envstudio.commands.common import (
    add_camera_option,
    add_scene_options,
    add_time_limit_option,
    parse_time_limit,
    session_from_args,
)
from envstudio.engine.hooks import Command
from envstudio.errors import ParameterError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Methods, scene, camera, size, parameters, stopping, timing, output, cache."""
    add_scene_options(parser)
    parser.add_argument("--methods", required=True, help="comma-separated method names")
    add_camera_option(parser)
    parser.add_argument("--size", default="256x256", help="WIDTHxHEIGHT (default 256x256)")
    parser.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="parameter for every method that declares it, the reference's included "
        "(repeatable), e.g. phong_exponent=50 or max_samples=1024",
    )
    parser.add_argument(
        "--strict",
        action="store_true",
        help="accumulate the reference until its successive-half change is below tolerance "
        "(default: until its noise is under a tenth of every method's error; an explicit "
        "--param tolerance=... is strict too)",
    )
    add_time_limit_option(parser, "stop the reference after")
    parser.add_argument(
        "--ssaa",
        type=int,
        default=4,
        metavar="K",
        help="render each method at KxK samples per pixel, box-filtered, as the reference "
        "averages each pixel's footprint (default 4; 1: pixel centres; time is still per "
        "one-sample frame)",
    )
    parser.add_argument("--frames", type=int, default=20, help="timed frames per method")
    parser.add_argument("--warmup", type=int, default=3, help="untimed frames per method")
    parser.add_argument("--out", required=True, help="folder for the images, table and index.html")
    parser.add_argument(
        "--reference",
        choices=("exact", "montecarlo"),
        default="exact",
        help="exact (default): a reflectance model with an exact untraced evaluation (phong, "
        "microfacet, banks) "
        "is evaluated exactly at the methods' samples wherever the untraced model is wanted "
        "(the reference itself with trace=false, the approximation column with trace=true); "
        "other models, and the traced reference, by Monte Carlo; montecarlo: Monte Carlo "
        "throughout",
    )
    parser.add_argument(
        "--no-decompose",
        dest="decompose",
        action="store_false",
        help="where the reference traces, do not also accumulate it untraced (no approximation "
        "error and scene-only columns)",
    )
    parser.add_argument(
        "--no-cache",
        dest="cache",
        action="store_false",
        help="neither resume nor save the reference's accumulation "
        "(default: kept in $ENVSTUDIO_CACHE_DIR or ~/.cache/envstudio)",
    )


def run(args: argparse.Namespace) -> int:
    """Measure, write the report, print the table and any warning."""
    from envstudio.core.metrics import MIN_SIZE
    from envstudio.io.atomic import check_output_folder
    from envstudio.io.scene_setup import parse_camera, parse_size
    from envstudio.measure.compare import (
        check_ssaa,
        method_classes,
        plan_parameters,
        run_comparison,
    )
    from envstudio.measure.report import format_table, write_report

    size = parse_size(args.size)
    if min(size) < MIN_SIZE:
        raise ParameterError(f"--size {args.size}: compare needs at least {MIN_SIZE}x{MIN_SIZE}")
    names = [name.strip() for name in args.methods.split(",") if name.strip()]
    if not names:
        raise ParameterError(f"--methods {args.methods!r}: expected comma-separated method names")
    plan = plan_parameters(method_classes(names), args.param)
    if args.frames < 1 or args.warmup < 0:
        raise ParameterError("--frames must be >= 1 and --warmup >= 0")
    time_limit = parse_time_limit(args.time_limit)
    check_ssaa(args.ssaa, size, "--ssaa")
    out = check_output_folder(args.out)
    if args.camera:
        parse_camera(args.camera)
    session = session_from_args(args)
    try:
        comparison = run_comparison(
            session,
            names,
            size,
            plan,
            args.frames,
            args.warmup,
            progress=sys.stderr.isatty(),
            cache=args.cache,
            strict=args.strict,
            time_limit_s=time_limit,
            extras_dir=out,
            ssaa=args.ssaa,
            decompose=args.decompose,
            reference_kind=args.reference,
        )
    finally:
        session.release()
    write_report(comparison, out)
    print(format_table(comparison))
    note = time_limit_note(comparison.reference)
    if note:
        print(f"envstudio: note: {note}", file=sys.stderr)
    if not comparison.reliable:
        print(
            f"envstudio: warning: metrics unreliable: {comparison.unreliable_reason}",
            file=sys.stderr,
        )
    return 0


def time_limit_note(reference) -> str | None:
    """One line when the time limit ended a strict (tolerance) run before it converged."""
    from envstudio.measure.stopping import TOLERANCE_RULE

    if reference.stopping_rule != TOLERANCE_RULE or reference.stopped_by != "time_limit":
        return None
    change = reference.status.rms_change
    reached = "no half-change measured" if change is None else f"half-change {100 * change:.3g} %"
    return (
        f"the time limit ({float(reference.parameters['time_limit']):g} s) ended before the "
        f"tolerance ({100 * float(reference.parameters['tolerance']):.3g} %): {reached} at "
        f"{reference.status.samples} spp, reported as NOT converged"
    )


COMMAND = Command(
    "compare",
    "measure methods against the converged reference (PSNR, SSIM, FLIP)",
    run,
    add_arguments,
)
