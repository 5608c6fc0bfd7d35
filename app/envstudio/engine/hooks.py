"""The hook types a plugin hands the program: its method and what it adds to the commands.

A :class:`Plugin` bundles one :class:`~envstudio.engine.method.Method` subclass
with its subcommands (:class:`Command`), figures (:class:`Figure`), offline
bakes (:class:`Bake`) and bench tables (:class:`BenchTable`). The generic
commands know methods only through these: ``envstudio figure NAME`` lists every
plugin's figures, ``envstudio bake KIND`` every bake, ``envstudio bench`` every
table's flag. Report sections and panel figures are methods of the class itself
(:meth:`Method.report_extras`, :meth:`Method.panel_images`).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from envstudio.engine.method import Method, Session

#: Adds a command's own options to its parser.
AddArguments = Callable[[argparse.ArgumentParser], None]


def _no_arguments(parser: argparse.ArgumentParser) -> None:
    """A hook without options of its own."""


@dataclass(frozen=True)
class Command:
    """A subcommand, ``envstudio NAME ...``.

    Attributes
    ----------
    name : str
        The subcommand's name.
    help : str
        One line for ``envstudio --help``.
    run : callable
        ``run(args) -> int``: does the work and returns the exit status; bad input
        raises :class:`~envstudio.errors.UserError` (one line, exit status 2).
    add_arguments : callable
        ``add_arguments(parser)`` declares the options.
    """

    name: str
    help: str
    run: Callable[[argparse.Namespace], int]
    add_arguments: AddArguments = _no_arguments


@dataclass
class FigureRequest:
    """What ``envstudio figure NAME`` hands a figure.

    Attributes
    ----------
    session : Session or None
        The scene of ``--scene/--env/--mesh`` on the GPU, with ``--camera``
        applied (None for a figure declared ``gl=False``).
    size : (int, int)
        One panel's (width, height) in pixels (``--size``).
    output : Path
        The PNG to write (checked writable).
    assignments : list of str
        ``--param name=value`` as given.
    """

    session: Session | None
    size: tuple[int, int]
    output: Path
    assignments: list[str] = field(default_factory=list)

    def method(self, name: str, defaults: dict | None = None) -> Method:
        """The session's method ``name`` with ``defaults``, then ``--param``, applied."""
        method = self.session.method(name)
        method.values.update(defaults or {})
        self.session.apply(method, self.assignments)
        return method


@dataclass(frozen=True)
class Figure:
    """A figure of a paper, ``envstudio figure NAME``.

    Attributes
    ----------
    name : str
        The figure's name on the command line.
    help : str
        What it shows, for ``envstudio figure --help``.
    draw : callable
        ``draw(request) -> list[str]``: writes ``request.output`` and returns
        the lines to print (the layout, the numbers measured).
    gl : bool
        False when it needs no GL context (the scene options do not apply).
    """

    name: str
    help: str
    draw: Callable[[FigureRequest], list[str]]
    gl: bool = True


@dataclass(frozen=True)
class Bake:
    """An offline bake, ``envstudio bake KIND ... -o FILE``.

    The bake command gives every kind ``--param`` and ``-o/--output``.

    Attributes
    ----------
    kind : str
        The bake's name on the command line.
    help : str
        One line for ``envstudio bake --help``.
    run : callable
        ``run(args) -> int``.
    add_arguments : callable
        ``add_arguments(parser)`` declares the kind's own options.
    """

    kind: str
    help: str
    run: Callable[[argparse.Namespace], int]
    add_arguments: AddArguments = _no_arguments


@dataclass(frozen=True)
class BenchTable:
    """A table of ``envstudio bench``, chosen by its flag (``--hwconv-table``).

    Attributes
    ----------
    flag : str
        The option that asks for it.
    help : str
        Its help text.
    run : callable
        ``run(args, session, size) -> int``: measures on the session of the scene
        options (its ``--param`` not applied: the table knows which method gets
        them) at the parsed ``--size`` (w, h), prints the table and writes
        ``args.json_out`` (checked writable, or None).
    add_arguments : callable
        ``add_arguments(parser)`` declares options only this table reads.
    """

    flag: str
    help: str
    run: Callable[[argparse.Namespace, Session, tuple[int, int]], int]
    add_arguments: AddArguments = _no_arguments

    @property
    def dest(self) -> str:
        """The attribute argparse stores the flag under."""
        return self.flag.lstrip("-").replace("-", "_")


@dataclass(frozen=True)
class Plugin:
    """A method with everything it adds to the program.

    An entry point of the group ``envstudio.methods`` names either a
    :class:`Method` subclass (a plugin of that method alone) or one of these.

    Attributes
    ----------
    method : type of Method
        The renderer.
    order : float
        Its place among the methods of its distribution: in the switch, on the
        keys 1–9 and in ``envstudio methods`` (methods of other distributions
        come after envmap-studio's).
    ground_truth : bool
        The method ``compare`` measures the others against (the shipped
        ``reference``; it must implement :class:`envstudio.measure.ground_truth.GroundTruth`).
    shaders : Path or None
        The plugin's GLSL folder: its files load as ``<folder name>/<file>``,
        and ``#include`` finds them, and the shipped ``common/`` files, by that name.
    commands, figures, bakes, bench_tables : tuple
        What it adds to ``envstudio``'s subcommands.
    """

    method: type[Method]
    order: float = 0.0
    ground_truth: bool = False
    shaders: Path | None = None
    commands: tuple[Command, ...] = ()
    figures: tuple[Figure, ...] = ()
    bakes: tuple[Bake, ...] = ()
    bench_tables: tuple[BenchTable, ...] = ()

    @property
    def name(self) -> str:
        """The method's name."""
        return self.method.name
