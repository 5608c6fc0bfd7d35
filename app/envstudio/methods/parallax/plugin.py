"""Plugin ``parallax``: ordered by its talk's date (SIGGRAPH, August 2012)."""

from envstudio.methods.parallax.method import ParallaxMethod
from envstudio.plugin import Plugin

PLUGIN = Plugin(ParallaxMethod, order=2012.08)
