"""Plugin ``splitsum``: Karis's split sum (SIGGRAPH 2013 course, July 2013)."""

from envstudio.methods.splitsum.method import SplitSumMethod
from envstudio.plugin import Plugin

PLUGIN = Plugin(SplitSumMethod, order=2013.07)
