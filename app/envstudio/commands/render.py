"""``envstudio render``: one frame headless through EGL, PNG as displayed or EXR linear."""

from __future__ import annotations

import argparse

from envstudio.commands.common import (
    add_camera_option,
    add_param_option,
    add_scene_options,
    add_time_limit_option,
    parse_time_limit,
    session_from_args,
)
from envstudio.engine.hooks import Command
from envstudio.engine.session import render_until_finished
from envstudio.errors import ParameterError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The scene, the method and its parameters, camera, size, time limit, output."""
    add_scene_options(parser)
    parser.add_argument("--method", default="mirror", help="method name (envstudio methods)")
    add_param_option(parser)
    add_camera_option(parser)
    parser.add_argument("--size", default="512x512", help="WIDTHxHEIGHT (default 512x512)")
    add_time_limit_option(parser, "progressive methods (reference): stop accumulating after")
    parser.add_argument("-o", "--output", required=True, help="OUT.png (as displayed) or OUT.exr")


def run(args: argparse.Namespace) -> int:
    """Render until the method is finished, write the image, print one line."""
    from envstudio.engine.registry import method_class
    from envstudio.io.atomic import check_output_path
    from envstudio.io.images import write_image
    from envstudio.io.scene_setup import parse_camera, parse_size

    size = parse_size(args.size)
    output = check_output_path(args.output)
    if output.suffix.lower() not in (".png", ".exr"):
        raise ParameterError(f"-o {output}: expected a .png or .exr file name")
    declared = {p.name for p in method_class(args.method).parameters}
    time_limit = parse_time_limit(args.time_limit)
    if time_limit is not None and "time_limit" not in declared:
        raise ParameterError(
            f"--time-limit: method {args.method} draws its image in one frame "
            "(only progressive methods, such as reference, take a time limit)"
        )
    if args.camera:
        parse_camera(args.camera)
    session = session_from_args(args)
    try:
        method = session.method(args.method)
        session.apply(method, args.param)
        if time_limit is not None:
            method.values["time_limit"] = time_limit
        stats = render_until_finished(session, method, size)
        pixels = session.read_hdr() if output.suffix.lower() == ".exr" else session.read_ldr()
        write_image(output, pixels)
    finally:
        session.release()
    print(f"{output}: {args.method} {size[0]}x{size[1]} in {stats.total_ms:.1f} ms ({stats.clock})")
    return 0


COMMAND = Command("render", "render one frame headless (EGL)", run, add_arguments)
