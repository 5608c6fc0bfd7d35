"""``envstudio atlas``: every method × environment × shape × glossiness on one page."""

from __future__ import annotations

import argparse
import sys

from envstudio.commands.common import add_param_option
from envstudio.engine.hooks import Command
from envstudio.errors import ParameterError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The grid's lists, its settings, parallelism, the output folder."""
    parser.add_argument(
        "--methods", help="comma-separated methods (default: every one but the reference)"
    )
    parser.add_argument(
        "--envs", help="shipped environment names or .exr/.hdr files (default: all shipped)"
    )
    parser.add_argument(
        "--meshes",
        default="sphere,knot",
        help="sphere, knot, bunny or mesh files (default: sphere,knot)",
    )
    parser.add_argument("--exponents", default="10,100,1000", help="Phong exponents N")
    parser.add_argument("--kd", default="0", help="diffuse weights k_d (default 0)")
    parser.add_argument("--size", default="96x96", help="WIDTHxHEIGHT (default 96x96)")
    parser.add_argument(
        "--cameras", type=int, default=1, help="K cameras spread in azimuth (default 1)"
    )
    parser.add_argument(
        "--time-limit",
        type=float,
        default=60.0,
        metavar="SECONDS",
        help="the reference's time limit per scene (default 60)",
    )
    parser.add_argument(
        "--ssaa", type=int, default=4, help="samples per pixel per axis, as compare (default 4)"
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
    """Measure the missing cells, write the page; exit 1 if any cell failed."""
    from envstudio.engine.registry import available_methods, ground_truth_class
    from envstudio.io.atomic import check_output_folder
    from envstudio.io.scene_file import shipped_environments
    from envstudio.io.scene_setup import parse_size
    from envstudio.measure.atlas.grid import AtlasGrid
    from envstudio.measure.atlas.run import run_atlas

    if args.jobs < 1:
        raise ParameterError(f"--jobs {args.jobs}: expected at least 1")
    if not args.time_limit > 0:
        raise ParameterError(f"--time-limit {args.time_limit}: expected a positive number")
    truth = ground_truth_class().name
    methods = _names(args.methods, "--methods") or [n for n in available_methods() if n != truth]
    grid = AtlasGrid(
        methods=tuple(methods),
        envs=tuple(_names(args.envs, "--envs") or shipped_environments()),
        meshes=tuple(_names(args.meshes, "--meshes")),
        exponents=tuple(_numbers(args.exponents, "--exponents")),
        kds=tuple(_numbers(args.kd, "--kd")),
        size=parse_size(args.size),
        cameras=args.cameras,
        time_limit=args.time_limit,
        ssaa=args.ssaa,
        params=tuple(args.param),
    )
    from envstudio.measure.compare import method_classes, plan_parameters

    plan_parameters(method_classes(list(grid.methods)), grid.params)  # one line if bad
    out = check_output_folder(args.out)
    result = run_atlas(grid, out, args.jobs, args.scheduler, args.force, sys.stderr.isatty())
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


def _names(text: str | None, option: str) -> list[str]:
    if text is None:
        return []
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise ParameterError(f"{option} {text!r}: expected comma-separated names")
    return names


def _numbers(text: str, option: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise ParameterError(f"{option} {text}: expected comma-separated numbers") from None
    return values


COMMAND = Command(
    "atlas",
    "every method x environment x shape x glossiness on one page (index.html, atlas.json)",
    run,
    add_arguments,
)
