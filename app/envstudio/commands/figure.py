"""``envstudio figure NAME``: a paper's figure, from the plugin that declares it."""

from __future__ import annotations

import argparse

from envstudio.commands.common import (
    add_camera_option,
    add_param_option,
    add_scene_options,
    session_from_args,
)
from envstudio.engine.hooks import Command, FigureRequest
from envstudio.engine.registry import registry
from envstudio.errors import ParameterError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """NAME (every plugin's figures), the scene, parameters, camera, panel size, output."""
    figures = registry().hooks("figures")
    parser.add_argument(
        "name",
        choices=tuple(figures),
        help="; ".join(f"{name}: {figure.help}" for name, (_, figure) in figures.items()),
    )
    add_scene_options(parser)
    add_param_option(parser)
    add_camera_option(parser)
    parser.add_argument("--size", default="192x192", help="one panel, WIDTHxHEIGHT")
    parser.add_argument("-o", "--output", required=True, help="OUT.png")


def run(args: argparse.Namespace) -> int:
    """Check size and output, make the session the figure needs, draw, print its lines."""
    from envstudio.io.atomic import check_output_path
    from envstudio.io.scene_setup import parse_size

    _, figure = registry().hooks("figures")[args.name]
    size = parse_size(args.size)
    output = check_output_path(args.output)
    if output.suffix.lower() != ".png":
        raise ParameterError(f"-o {output}: expected a .png file name")
    if not figure.gl:
        lines = figure.draw(FigureRequest(None, size, output, list(args.param)))
    else:
        session = session_from_args(args)
        try:
            lines = figure.draw(FigureRequest(session, size, output, list(args.param)))
        finally:
            session.release()
    for line in lines:
        print(line)
    return 0


COMMAND = Command("figure", "render a figure of a seed paper", run, add_arguments)
