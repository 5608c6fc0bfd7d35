"""Plugin ``mirror``: the baseline, first in the switch."""

from envstudio.methods.mirror.method import MirrorMethod
from envstudio.plugin import Plugin

PLUGIN = Plugin(MirrorMethod, order=0.0)
