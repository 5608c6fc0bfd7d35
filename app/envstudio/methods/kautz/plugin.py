"""Plugin ``kautz``: seed 000 (Kautz, Daubert, Seidel; Computers & Graphics 28(1), 2004)."""

from envstudio.methods.kautz import figures
from envstudio.methods.kautz.method import KautzMethod
from envstudio.plugin import Plugin

PLUGIN = Plugin(KautzMethod, order=2004.02, figures=(figures.GRID, figures.SEAMS))
