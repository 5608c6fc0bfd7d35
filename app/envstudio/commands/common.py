"""What several subcommands share: the scene and parameter options, the time limit,
a session of the scene the options name, rendering until a method is finished."""

from __future__ import annotations

import argparse


def add_scene_options(parser: argparse.ArgumentParser) -> None:
    """``--scene``, ``--env`` and ``--mesh``."""
    parser.add_argument("--scene", help="shipped scene name (studio, room) or a TOML scene file")
    parser.add_argument("--env", help="lat-long environment (.exr or .hdr), replaces the scene's")
    parser.add_argument(
        "--mesh", help="mesh file (OBJ, PLY, STL, OFF, GLB), replaces the reflector"
    )
    add_env_width_option(parser)


def add_env_width_option(parser: argparse.ArgumentParser) -> None:
    """``--max-env-width W``: box-filter a larger environment as it is read."""
    parser.add_argument(
        "--max-env-width",
        type=int,
        metavar="W",
        help="box-filter the environment to at most W texels wide as it is read "
        "(for maps larger than the memory available)",
    )


def add_param_option(parser: argparse.ArgumentParser) -> None:
    """``--param NAME=VALUE`` (repeatable)."""
    parser.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="method or display parameter (repeatable), e.g. lod_bias=2.3",
    )


def add_time_limit_option(parser: argparse.ArgumentParser, what: str) -> None:
    """``--time-limit SECONDS`` for a progressive ground truth."""
    parser.add_argument(
        "--time-limit",
        metavar="SECONDS",
        help=f"{what} this many seconds and report the noise reached (a positive number)",
    )


def add_camera_option(parser: argparse.ArgumentParser) -> None:
    """``--camera AZIMUTH,ELEVATION,DISTANCE``."""
    parser.add_argument("--camera", help="AZIMUTH,ELEVATION,DISTANCE in degrees and scene units")


def parse_time_limit(text: str | None) -> float | None:
    """``--time-limit SECONDS`` as a float (None when not given).

    Raises
    ------
    ParameterError
        Unless a finite number > 0 and at most the ground truth's ``time_limit`` maximum
        (:func:`envstudio.measure.time_limit.check_time_limit`).
    """
    from envstudio.measure.time_limit import check_time_limit

    return None if text is None else check_time_limit(text, "--time-limit")


def session_from_args(args: argparse.Namespace, scene=None):
    """A :class:`~envstudio.engine.session.RenderSession` of ``scene`` (default: the scene
    options'), with ``--camera`` applied when the command has it."""
    from envstudio.engine.session import RenderSession
    from envstudio.io.scene_setup import build_scene, parse_camera

    camera = parse_camera(args.camera) if getattr(args, "camera", None) else None
    session = RenderSession(
        scene or build_scene(args.scene, args.env, args.mesh, args.max_env_width)
    )
    if camera:
        session.camera.azimuth, session.camera.elevation, session.camera.distance = camera
    return session
