"""envmap-studio: classic environment-map reflection techniques side by side.

As a library (``import envstudio as es``): :func:`load_scene`, :func:`render`,
:func:`display`, :func:`compare` and :func:`show` (envstudio/api.py), loaded on first use
so that ``import envstudio`` stays light; the errors they raise are :class:`UserError`'s.
"""

from importlib.metadata import PackageNotFoundError, version

try:  # one source of truth: pyproject.toml's version, as installed
    __version__ = version("envmap-studio")
except PackageNotFoundError:  # imported from a checkout that was never installed
    __version__ = "0+unknown"

_API = ("load_scene", "render", "display", "compare", "error_curve", "show", "Image", "Report")


def __getattr__(name: str):
    """The library API and the user errors, imported when first asked for."""
    if name in _API:
        from envstudio import api

        return getattr(api, name)
    if name in ("UserError", "InputFileError", "ParameterError", "OutputFileError"):
        from envstudio import errors

        return getattr(errors, name)
    raise AttributeError(f"module 'envstudio' has no attribute {name!r}")
