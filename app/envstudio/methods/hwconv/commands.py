"""``envstudio bench --methods hwconv --hwconv-table | --hwconv-accuracy``: seed 004 §5.2's
table and the kernels' error against the brute-force Phong prefilter."""

from __future__ import annotations

import argparse
import json
import sys

from envstudio.io.atomic import write_text_atomic
from envstudio.methods.hwconv.accuracy import (
    format_accuracy,
    format_error_images,
    run_accuracy,
    write_error_images,
)
from envstudio.methods.hwconv.bench import format_table, run_table
from envstudio.plugin import BenchTable, ParameterError, Session


def _exponents(args: argparse.Namespace) -> list[float]:
    try:
        return [float(e) for e in args.exponents.split(",")]
    except ValueError:
        raise ParameterError(f"--exponents {args.exponents}: expected numbers > 0") from None


def _method(session: Session, args: argparse.Namespace):
    method = session.method("hwconv")
    method.values["map_size"] = 512  # the paper's; --param overrides
    session.apply(method, args.param)
    return method


def run_table_command(args: argparse.Namespace, session: Session, size: tuple[int, int]) -> int:
    """``--hwconv-table``: filter sizes, shrink factors and times beside the paper's."""
    exponents = _exponents(args)
    _method(session, args)
    report = run_table(
        session, exponents, size, args.frames, args.warmup, progress=sys.stderr.isatty()
    )
    print(format_table(report))
    if args.json_out:
        write_text_atomic(args.json_out, json.dumps(report, indent=2))
    return 0


def run_accuracy_command(args: argparse.Namespace, session: Session, size: tuple[int, int]) -> int:
    """``--hwconv-accuracy``: RMS and max relative error per exponent, error images by the JSON."""
    if args.directions < 1:
        raise ParameterError(f"--directions {args.directions}: expected an integer >= 1")
    exponents = _exponents(args)
    _method(session, args)
    errors: dict = {}
    report = run_accuracy(
        session, exponents, args.directions, progress=sys.stderr.isatty(), errors=errors
    )
    print(format_accuracy(report))
    if args.json_out:  # the error images beside OUT, listed in it
        images = write_error_images(report, errors, args.json_out)
        report["error_images"] = {"scale": 1.0, "files": [p.name for p in images]}
        print(format_error_images(images, 1.0))
        write_text_atomic(args.json_out, json.dumps(report, indent=2))
    return 0


def add_accuracy_arguments(parser: argparse.ArgumentParser) -> None:
    """``--directions``, read by ``--hwconv-accuracy`` alone."""
    parser.add_argument(
        "--directions",
        type=int,
        default=8192,
        help="with --hwconv-accuracy: lookup directions over the sphere (default 8192)",
    )


TABLE = BenchTable(
    "--hwconv-table",
    "seed 004 §5.2's table for --methods hwconv: filter sizes and shrink factors "
    "beside the paper's, refilter + render per frame (2-pass, 1-pass) over the static map",
    run_table_command,
)
ACCURACY = BenchTable(
    "--hwconv-accuracy",
    "for --methods hwconv: RMS and max relative error of 2-pass, 1-pass and exact "
    "against the brute-force Phong prefilter at --exponents (map_size 512 unless --param); "
    "with --json, the error images per exponent as PNGs beside it (OUT.error_N<N>.png)",
    run_accuracy_command,
    add_accuracy_arguments,
)
