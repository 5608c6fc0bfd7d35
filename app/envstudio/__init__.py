"""envmap-studio: classic environment-map reflection techniques side by side."""

__version__ = "0.1.0"
