"""``envstudio bench``: time per frame and per pass of every method; or a table: the
ground truth's convergence (``--converge``), the prefilter's (``--prefilter``), or a
method's own (its plugin's flag, e.g. ``--hwconv-table``)."""

from __future__ import annotations

import argparse
import json
import sys

from envstudio.commands.common import add_param_option, add_scene_options, session_from_args
from envstudio.engine.hooks import Command
from envstudio.engine.registry import registry
from envstudio.errors import ParameterError

#: The most triangles ``--triangles`` asks for (about 2 GB of mesh while subdividing).
MAX_TRIANGLES = 20_000_000


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The generic options, then every plugin's table flag and its own options."""
    add_scene_options(parser)
    parser.add_argument(
        "--methods",
        help="comma-separated method names (default: all but the progressive reference, "
        "whose frame is one batch; see --converge)",
    )
    parser.add_argument(
        "--size",
        help="WIDTHxHEIGHT (default 1280x720); with --prefilter the paraboloid map, "
        "FACExWIDTH (default 128x256, two 128-texel faces)",
    )
    parser.add_argument("--frames", type=int, default=60, help="measured frames per method")
    parser.add_argument("--warmup", type=int, default=5, help="unmeasured frames per method")
    parser.add_argument(
        "--triangles",
        type=int,
        help=f"subdivide the reflector until it has at least this many triangles "
        f"(1..{MAX_TRIANGLES:,})",
    )
    parser.add_argument(
        "--converge",
        action="store_true",
        help="time the reference to its tolerance (successive-half change) instead",
    )
    parser.add_argument(
        "--time-limit",
        type=float,
        default=3600.0,
        help="with --converge: stop after this many seconds and project the rest",
    )
    parser.add_argument(
        "--resume",
        action="store_true",
        help="with --converge: continue the saved accumulation of an earlier run of the same "
        "inputs and save this one every minute (seconds then count all the runs)",
    )
    parser.add_argument(
        "--prefilter",
        action="store_true",
        help="seed 004 §5.1's table instead: brute-force vs hierarchical Phong prefilter "
        "(CPU), and with --json the time-against-size plot as PNG beside it",
    )
    parser.add_argument(
        "--chain",
        action="store_true",
        help="with --prefilter: the Phong cube mip chains instead, spectral (CPU) and GPU "
        "(8 levels at 128² and 256², time against cmft's and every level's error to the "
        "brute force)",
    )
    parser.add_argument(
        "--exponents",
        default="10,50,100,250,500",
        help="with --prefilter or a method's table: comma-separated Phong exponents "
        "(default 10,50,100,250,500)",
    )
    for _, table in registry().hooks("bench_tables").values():
        parser.add_argument(table.flag, action="store_true", help=table.help)
        table.add_arguments(parser)
    add_param_option(parser)
    parser.add_argument("--json", dest="json_out", help="write the report as JSON here")


def default_bench_methods() -> list[str]:
    """What ``bench`` times without ``--methods``: every method that draws its image in one frame.

    A progressive method's frame is one batch of an accumulation (a reference
    batch at 1280x720 takes seconds on a software renderer); name it with
    ``--methods`` to time its batches, or use ``bench --converge``.
    """
    from envstudio.engine.registry import available_methods

    return [name for name, cls in available_methods().items() if not cls.progressive]


def _check_frames(args: argparse.Namespace) -> None:
    if args.frames < 1 or args.warmup < 0:
        raise ParameterError("--frames must be >= 1 and --warmup >= 0")


def _json_out(args: argparse.Namespace):
    from envstudio.io.atomic import check_output_path

    return check_output_path(args.json_out, (".json",)) if args.json_out else None


def _report(text: str, report: dict, json_out) -> int:
    """Print the table and write the JSON where asked; the exit status."""
    from envstudio.io.atomic import write_text_atomic

    print(text)
    if json_out:
        write_text_atomic(json_out, json.dumps(report, indent=2))
    return 0


def run(args: argparse.Namespace) -> int:
    """Dispatch to the table asked for, else time the methods."""
    from envstudio.io.scene_setup import parse_size

    if args.prefilter:
        from envstudio.commands.prefilter import run_prefilter_bench

        return run_prefilter_bench(args)
    size = parse_size(args.size or "1280x720")
    tables = [(owner, t) for owner, t in registry().hooks("bench_tables").values()]
    asked = [(owner, t) for owner, t in tables if getattr(args, t.dest)]
    if len(asked) > 1:
        raise ParameterError(f"{' '.join(t.flag for _, t in asked)}: expected one of them")
    if asked:
        return _run_table(args, size, *asked[0])
    if args.converge:
        return _run_convergence(args, size)
    if args.resume:
        raise ParameterError("--resume: only with --converge (it resumes a reference accumulation)")
    return _run_methods(args, size)


def _run_table(args: argparse.Namespace, size: tuple[int, int], owner: str, table) -> int:
    """A plugin's table, on a session of the scene options."""
    if args.methods not in (None, owner):
        raise ParameterError(f"{table.flag} --methods {args.methods}: only '{owner}' has it")
    _check_frames(args)
    args.json_out = _json_out(args)
    session = session_from_args(args)
    try:
        return table.run(args, session, size)
    finally:
        session.release()


def _run_methods(args: argparse.Namespace, size: tuple[int, int]) -> int:
    """Median and p95 time per frame and per pass of each method."""
    from envstudio.engine.display import DISPLAY_NAMES
    from envstudio.engine.registry import method_class
    from envstudio.io.scene_setup import build_scene, subdivide_reflectors
    from envstudio.measure.bench import format_report
    from envstudio.measure.bench import run_bench as bench

    names = default_bench_methods()
    if args.methods is not None:
        names = [name.strip() for name in args.methods.split(",") if name.strip()]
        if not names:
            raise ParameterError(
                f"--methods {args.methods!r}: expected comma-separated method names"
            )
    for name in names:
        method_class(name)
    if args.triangles is not None and not 1 <= args.triangles <= MAX_TRIANGLES:
        raise ParameterError(f"--triangles {args.triangles}: expected 1..{MAX_TRIANGLES:,}")
    _check_frames(args)
    json_out = _json_out(args)
    scene = build_scene(args.scene, args.env, args.mesh, args.max_env_width)
    if args.triangles:
        subdivide_reflectors(scene, args.triangles)
    session = session_from_args(args, scene)
    try:
        for name in names:
            method = session.method(name)
            own = [
                a
                for a in args.param
                if a.partition("=")[0] in method.values or a.partition("=")[0] in DISPLAY_NAMES
            ]
            session.apply(method, own)
        report = bench(session, names, size, args.frames, args.warmup, progress=sys.stderr.isatty())
    finally:
        session.release()
    return _report(format_report(report), report, json_out)


def _run_convergence(args: argparse.Namespace, size: tuple[int, int]) -> int:
    """``--converge``: the ground truth's time to its tolerance."""
    from envstudio.engine.registry import ground_truth_class
    from envstudio.measure.convergence import format_convergence, run_convergence

    truth = ground_truth_class().name
    if args.methods not in (None, truth):
        raise ParameterError(f"--converge --methods {args.methods}: only '{truth}' converges")
    if not args.time_limit > 0:
        raise ParameterError(f"--time-limit {args.time_limit}: expected a positive number")
    json_out = _json_out(args)
    session = session_from_args(args)
    try:
        method = session.method(truth)
        session.apply(method, args.param)
        report = run_convergence(
            session,
            method,
            size,
            args.time_limit,
            progress=sys.stderr.isatty(),
            resume=args.resume,
        )
    finally:
        session.release()
    return _report(format_convergence(report), report, json_out)


COMMAND = Command("bench", "time every method per frame and per pass", run, add_arguments)
