"""Plugin ``reference``: the ground truth every other method is measured against, last."""

from envstudio.methods.reference.method import ReferenceMethod
from envstudio.plugin import Plugin

PLUGIN = Plugin(ReferenceMethod, order=float("inf"), ground_truth=True)
