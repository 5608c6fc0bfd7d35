"""Plugin ``pem``: seed 003 (Hakura, Snyder, Lengyel; I3D, March 2001)."""

from envstudio.methods.pem import commands, figures
from envstudio.methods.pem.method import PemMethod
from envstudio.plugin import Plugin

PLUGIN = Plugin(
    PemMethod,
    order=2001.03,
    figures=(figures.OFFMANIFOLD, figures.MAPS),
    bakes=(commands.BAKE,),
)
