"""The ``envstudio`` command: view (default), render, methods, bench, sh, figure, doctor, …

The parser is built from :mod:`envstudio.commands` and the plugins' own commands
(:mod:`envstudio.engine.registry`). Usage errors print one line and exit with
status 2; nothing prints a traceback for bad input.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
from collections.abc import Sequence
from pathlib import Path

from envstudio.errors import ContextError, InputFileError, ParameterError, UserError, file_error


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (exit status 2)."""

    def error(self, message: str):
        raise ParameterError(f"{self.prog}: {message}")


def _commands():
    """Every subcommand: envmap-studio's, then the plugins' (a name taken is left out)."""
    from envstudio.commands import builtin_commands
    from envstudio.engine.registry import registry

    commands = builtin_commands()
    taken = {command.name for command in commands}
    for owner, command in registry().hooks("commands").values():
        if command.name in taken:
            print(
                f"envstudio: warning: method {owner}'s command {command.name!r} is a built-in "
                "command's name; left out",
                file=sys.stderr,
            )
            continue
        commands.append(command)
    return commands


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    from envstudio import __version__

    parser = _Parser(prog="envstudio", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", parser_class=_Parser)
    for command in _commands():
        command.add_arguments(sub.add_parser(command.name, help=command.help))
        sub.choices[command.name].set_defaults(run=command.run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit status.

    SIGTERM is handled like Ctrl-C, so a killed ``compare`` or ``bench
    --converge --resume`` saves its reference accumulation before it exits.
    """
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        if argv[:1] == ["doctor"]:  # before the commands' imports, which may be what is missing
            from envstudio.doctor import run_doctor

            _Parser(prog="envstudio doctor").parse_args(argv[1:])
            return run_doctor()
        parser = build_parser()
        argv = _file_means_view(argv, parser)
        args = parser.parse_args(argv)
        if args.command is None:
            args = parser.parse_args(["view", *argv])
        return args.run(args) or 0
    except ContextError as exc:  # no GL (or no display): what is missing, and who says more
        print(f"envstudio: error: {exc} (`envstudio doctor` checks this machine)", file=sys.stderr)
        return exc.exit_code
    except UserError as exc:
        print(f"envstudio: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except OSError as exc:
        line = file_error(exc)
        if line is None:
            raise
        print(f"envstudio: error: {line}", file=sys.stderr)
        return InputFileError.exit_code
    except KeyboardInterrupt:
        print("envstudio: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `envstudio methods | head`: the reader left; say nothing more
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1


def _file_means_view(argv: list[str], parser: argparse.ArgumentParser) -> list[str]:
    """``envstudio FILE.exr`` is ``envstudio view FILE.exr`` (what a file manager runs)."""
    from envstudio.commands.view import file_suffixes

    if not argv or argv[0].startswith("-"):
        return argv
    subcommands = next(
        a.choices for a in parser._actions if isinstance(a, argparse._SubParsersAction)
    )
    if argv[0] in subcommands:
        return argv
    if Path(argv[0]).suffix.lower() in file_suffixes():
        return ["view", *argv]
    return argv


if __name__ == "__main__":
    sys.exit(main())
