"""Plugin ``banks``: seed 004 §5.3, after hwconv's §5.2 of the same paper (June 2000)."""

from envstudio.methods.banks import figures
from envstudio.methods.banks.method import BanksMethod
from envstudio.plugin import Plugin

PLUGIN = Plugin(BanksMethod, order=2000.061, figures=(figures.SLICES,))
