"""Plugin ``rsibr``: seed 002 (Cabral, Olano, Nemec; SIGGRAPH, August 1999)."""

from envstudio.methods.rsibr import commands, figures
from envstudio.methods.rsibr.method import RsibrMethod
from envstudio.plugin import Plugin

PLUGIN = Plugin(RsibrMethod, order=1999.08, figures=(figures.WARP,), bakes=(commands.BAKE,))
