"""``envstudio envmap``: the environment converted on the GPU, saved as linear EXR."""

from __future__ import annotations

import argparse

from envstudio.commands.common import add_env_width_option
from envstudio.commands.map_size import default_size
from envstudio.engine.hooks import Command
from envstudio.errors import ParameterError

#: ``--size`` when not given (more for a border that needs it: ``default_size``).
DEFAULT_SIZE = 256


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The environment, the representation, its size and border, the output."""
    parser.add_argument("--env", required=True, help="lat-long environment (.exr or .hdr)")
    add_env_width_option(parser)
    parser.add_argument(
        "--to",
        required=True,
        choices=("latlong", "cube", "paraboloid", "spheremap"),
        help="representation (cube: horizontal cross; paraboloid: front | back)",
    )
    parser.add_argument(
        "--size",
        type=int,
        help=f"face / output edge in texels (default {DEFAULT_SIZE}, or 2 * border + 2 for a "
        "wider --border)",
    )
    parser.add_argument("--border", type=int, default=0, help="paraboloid border in texels")
    parser.add_argument("-o", "--output", required=True, help="OUT.exr")


def run(args: argparse.Namespace) -> int:
    """Convert and write; print one line."""
    from envstudio.envmap.conversions import upload_latlong
    from envstudio.envmap.export import export_environment
    from envstudio.gpu.context import create_headless_context
    from envstudio.gpu.programs import ProgramLibrary
    from envstudio.io.atomic import check_output_path
    from envstudio.io.images import read_environment

    output = check_output_path(args.output)
    if output.suffix.lower() != ".exr":
        raise ParameterError(f"-o {output}: expected an .exr file name")
    args.size = default_size(args.size, args.border, DEFAULT_SIZE)
    if not 1 <= args.size <= 8192 or not 0 <= args.border < args.size // 2:
        raise ParameterError(
            f"--size {args.size} --border {args.border}: expected 1..8192 and 0 <= border < size/2"
        )
    radiance = read_environment(args.env, args.max_env_width)
    ctx = create_headless_context()
    programs = ProgramLibrary(ctx)
    try:
        latlong = upload_latlong(ctx, radiance)
        path = export_environment(ctx, programs, latlong, args.to, args.size, args.border, output)
    finally:
        programs.release()
        ctx.release()
    print(f"{path}: {args.to} from {args.env}")
    return 0


COMMAND = Command("envmap", "convert an environment (GPU) and save it as EXR", run, add_arguments)
