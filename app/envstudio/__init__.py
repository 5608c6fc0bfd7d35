"""envmap-studio: classic environment-map reflection techniques side by side."""

from importlib.metadata import PackageNotFoundError, version

try:  # one source of truth: pyproject.toml's version, as installed
    __version__ = version("envmap-studio")
except PackageNotFoundError:  # imported from a checkout that was never installed
    __version__ = "0+unknown"
