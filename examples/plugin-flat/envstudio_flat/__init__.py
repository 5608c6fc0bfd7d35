"""An example envmap-studio plugin: method ``flat`` and its figure ``flat-swatches``.

Written against :mod:`envstudio.plugin` alone, as any package of your own would be.
"""

from pathlib import Path

from envstudio.plugin import Plugin
from envstudio_flat.figure import SWATCHES
from envstudio_flat.method import FlatMethod

PLUGIN = Plugin(
    FlatMethod,
    order=1.0,
    shaders=Path(__file__).parent / "shaders" / "flat",
    figures=(SWATCHES,),
)
