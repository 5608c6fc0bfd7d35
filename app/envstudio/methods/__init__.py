"""Renderers: one module per method, each registers itself with its declared parameters."""

from envstudio.methods import kautz, mirror, reference  # noqa: F401
