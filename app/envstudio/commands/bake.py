"""``envstudio bake KIND``: the offline bakes the plugins declare (rsibr, pem, …)."""

from __future__ import annotations

import argparse

from envstudio.commands.common import add_param_option
from envstudio.engine.hooks import Command
from envstudio.engine.registry import registry


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """One sub-parser per bake kind, each with its own options, ``--param`` and ``-o``."""
    kinds = parser.add_subparsers(dest="kind", metavar="KIND", required=True)
    for owner, bake in registry().hooks("bakes").values():
        kind = kinds.add_parser(bake.kind, help=f"{bake.help} (method {owner})")
        bake.add_arguments(kind)
        add_param_option(kind)
        kind.add_argument("-o", "--output", required=True, help=f"FILE.{bake.kind}")


def run(args: argparse.Namespace) -> int:
    """The bake of ``args.kind``."""
    _, bake = registry().hooks("bakes")[args.kind]
    return bake.run(args)


def bake_help() -> str:
    """The command's line in ``envstudio --help``: the kinds the plugins add."""
    kinds = ", ".join(
        f"{owner} {bake.kind}" if owner != bake.kind else bake.kind
        for owner, bake in registry().hooks("bakes").values()
    )
    return f"offline bakes of the methods: {kinds}"


def command() -> Command:
    """The command, its help naming the kinds registered now."""
    return Command("bake", bake_help(), run, add_arguments)
