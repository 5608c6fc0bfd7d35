"""``envstudio view [FILE]``: the desktop viewer (the default command)."""

from __future__ import annotations

import argparse
from pathlib import Path

from envstudio.commands.common import add_scene_options
from envstudio.engine.hooks import Command
from envstudio.errors import InputFileError, ParameterError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """FILE, the scene options, the first method, and the smoke tests' switches."""
    parser.add_argument(
        "file",
        nargs="?",
        help="an environment (.exr, .hdr), a mesh or a scene (.toml) to open: what a file "
        "manager passes (the desktop entry runs `envstudio view FILE`)",
    )
    add_scene_options(parser)
    parser.add_argument("--method", help="method shown first")
    parser.add_argument(
        "--frames", type=int, default=0, help="quit after this many frames (0: run until closed)"
    )
    parser.add_argument("--screenshot", help="save a screenshot (with the UI) before quitting")
    parser.add_argument(
        "--compare", metavar="METHOD", help="start in split screen against this method"
    )
    parser.add_argument(
        "--grid",
        nargs="?",
        const="all",
        metavar="METHODS",
        help="start in the grid view: every method, or these (comma-separated), in tiles",
    )
    parser.add_argument(
        "--hide-panels",
        action="store_true",
        help="start with the panels hidden (Tab shows them)",
    )
    parser.add_argument(
        "--cycle-methods",
        action="store_true",
        help="switch to the next method every few frames (smoke tests)",
    )


def file_suffixes() -> tuple[str, ...]:
    """Suffixes of the files the viewer opens: environments, meshes, scenes."""
    from envstudio.io.images import HDR_SUFFIXES
    from envstudio.io.meshes import MESH_SUFFIXES

    return (*HDR_SUFFIXES, *MESH_SUFFIXES, ".toml")


def open_file(args: argparse.Namespace) -> None:
    """``envstudio view FILE``: FILE becomes ``--env``, ``--mesh`` or ``--scene`` by its suffix.

    Raises
    ------
    InputFileError
        FILE does not exist.
    ParameterError
        FILE is of no kind the viewer opens, or the option it stands for is also given.
    """
    from envstudio.io.images import HDR_SUFFIXES
    from envstudio.io.meshes import MESH_SUFFIXES

    path = Path(args.file)
    suffix = path.suffix.lower()
    if suffix in HDR_SUFFIXES:
        option = "env"
    elif suffix in MESH_SUFFIXES:
        option = "mesh"
    elif suffix == ".toml":
        option = "scene"
    else:
        raise ParameterError(
            f"view {args.file}: expected a file of one of {', '.join(file_suffixes())}"
        )
    if not path.is_file():
        raise InputFileError(f"{args.file}: no such file")
    if getattr(args, option) is not None:
        raise ParameterError(f"view {args.file}: --{option} is given too; give one of them")
    setattr(args, option, str(path))


def run(args: argparse.Namespace) -> int:
    """Open the window."""
    if args.file:
        open_file(args)
    from envstudio.ui.app import run_viewer

    return run_viewer(args)


COMMAND = Command("view", "open the viewer window (the default)", run, add_arguments)
