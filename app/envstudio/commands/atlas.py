"""``envstudio atlas``: every method × environment × shape × glossiness on one page."""

from __future__ import annotations

import argparse
import sys

from envstudio.commands.common import add_param_option
from envstudio.engine.hooks import Command
from envstudio.errors import ParameterError
from envstudio.measure.compare import MAX_SSAA


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The grid's lists, its settings, parallelism, the output folder."""
    parser.add_argument(
        "--methods", help="comma-separated methods (default: every one but the reference)"
    )
    parser.add_argument(
        "--envs",
        help="shipped environment names or .exr/.hdr files (default: all shipped but "
        "studio_rgbe.hdr, the studio map stored as RGBE)",
    )
    parser.add_argument(
        "--meshes",
        default="sphere,knot",
        help="sphere, knot, bunny or mesh files (default: sphere,knot)",
    )
    parser.add_argument("--exponents", default="10,100,1000", help="Phong exponents N")
    parser.add_argument("--kd", default="0", help="diffuse weights k_d (default 0)")
    parser.add_argument("--size", default="96x96", help="WIDTHxHEIGHT (default 96x96)")
    parser.add_argument("--cameras", default="1", help="K cameras spread in azimuth (default 1)")
    parser.add_argument(
        "--time-limit",
        default="60",
        metavar="SECONDS",
        help="the reference's time limit per scene (default 60)",
    )
    parser.add_argument(
        "--ssaa",
        default="4",
        help=f"samples per pixel per axis, 1..{MAX_SSAA} as compare (default 4)",
    )
    parser.add_argument(
        "--reference",
        choices=("exact", "montecarlo"),
        default="exact",
        help="as compare's --reference (default exact)",
    )
    add_param_option(parser)
    parser.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    parser.add_argument(
        "--dask",
        dest="scheduler",
        action="store_const",
        const="local",
        help="run the scenes on a Dask LocalCluster of --jobs workers",
    )
    parser.add_argument("--scheduler", help="run the scenes on the Dask scheduler at ADDRESS")
    parser.add_argument(
        "--force", action="store_true", help="measure again in a folder of other settings"
    )
    parser.add_argument("--out", required=True, help="folder for index.html, atlas.json, ...")


def run(args: argparse.Namespace) -> int:
    """Check the whole grid, measure the missing cells, write the page; exit 1 if a cell failed."""
    from envstudio.io.atomic import check_output_folder
    from envstudio.measure.atlas.run import run_atlas

    if args.jobs < 1:
        raise ParameterError(f"--jobs {args.jobs}: expected at least 1")
    grid = grid_from_args(args)
    if not args.out.strip():
        raise ParameterError(f"--out {args.out!r}: expected a folder name")
    out = check_output_folder(args.out)
    result = run_atlas(grid, out, args.jobs, args.scheduler, args.force, sys.stderr.isatty())
    for note in result.notes:
        print(f"envstudio: note: {note}", file=sys.stderr)
    print(f"atlas: {len(result.rows)} cells ({result.measured} measured now) in {out}/index.html")
    if result.failed:
        failed = [r for r in result.rows if r.get("error")]
        print(
            f"envstudio: {result.failed} cell(s) failed, e.g. {failed[0]['method']} "
            f"({failed[0]['env']}, {failed[0]['mesh']}): {failed[0]['error']}",
            file=sys.stderr,
        )
        return 1
    return 0


def grid_from_args(args: argparse.Namespace):
    """The grid of the command line, checked whole before anything is written.

    Returns
    -------
    AtlasGrid
        Finite values in range, every environment, mesh, method and parameter loaded
        (measure.atlas.validate.check_grid).

    Raises
    ------
    ParameterError, InputFileError
        The first bad option, in one line.
    """
    from envstudio.engine.registry import available_methods, ground_truth_class
    from envstudio.io.scene_setup import parse_size
    from envstudio.measure.atlas.grid import AtlasGrid, default_envs
    from envstudio.measure.atlas.validate import check_grid

    truth = ground_truth_class().name
    methods = _names(args.methods, "--methods") or [n for n in available_methods() if n != truth]
    grid = AtlasGrid(
        methods=tuple(methods),
        envs=tuple(_names(args.envs, "--envs") or default_envs()),
        meshes=tuple(_names(args.meshes, "--meshes")),
        exponents=tuple(_numbers(args.exponents, "--exponents")),
        kds=tuple(_numbers(args.kd, "--kd")),
        size=parse_size(args.size),
        cameras=_number(args.cameras, "--cameras", int),
        time_limit=_number(args.time_limit, "--time-limit", float),
        ssaa=_number(args.ssaa, "--ssaa", int),
        params=tuple(args.param),
        reference=args.reference,
    )
    check_grid(grid)
    return grid


def _names(text: str | None, option: str) -> list[str]:
    if text is None:
        return []
    names = list(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))
    if not names:
        raise ParameterError(f"{option} {text!r}: expected comma-separated names")
    return names


def _numbers(text: str, option: str) -> list[float]:
    try:
        values = list(dict.fromkeys(float(v) for v in text.split(",")))
    except ValueError:
        raise ParameterError(f"{option} {text!r}: expected comma-separated numbers") from None
    return values


def _number(text: str, option: str, kind: type[int] | type[float]) -> int | float:
    try:
        return kind(text)
    except ValueError:
        raise ParameterError(f"{option} {text!r}: expected one {kind.__name__}") from None


COMMAND = Command(
    "atlas",
    "every method x environment x shape x glossiness on one page (index.html, atlas.json)",
    run,
    add_arguments,
)
