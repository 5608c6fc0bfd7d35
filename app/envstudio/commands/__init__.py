"""The subcommands, one module each; ``envstudio --help`` lists them in this order.

Each module defines a :class:`~envstudio.engine.hooks.Command` (the hook type a
plugin's own subcommands use too). ``bake``, ``figure`` and ``bench`` take
their kinds, names and tables from the plugins (:mod:`envstudio.engine.registry`).
"""

from __future__ import annotations

from envstudio.commands import (
    atlas,
    bake,
    bench,
    compare,
    diffuse,
    doctor,
    envmap,
    figure,
    fit_glossiness,
    methods,
    prefilter,
    render,
    sh,
    view,
)
from envstudio.engine.hooks import Command


def builtin_commands() -> list[Command]:
    """envmap-studio's own subcommands, in ``--help`` order."""
    return [
        doctor.COMMAND,
        view.COMMAND,
        render.COMMAND,
        envmap.COMMAND,
        methods.COMMAND,
        bench.COMMAND,
        prefilter.COMMAND,
        compare.COMMAND,
        atlas.COMMAND,
        fit_glossiness.COMMAND,
        sh.COMMAND,
        diffuse.COMMAND,
        bake.command(),
        figure.COMMAND,
    ]
