"""Viewer settings persisted between runs in the user config directory.

Stored as JSON (``settings.json``), written atomically. A file that cannot be
read or parsed is reported in one line, moved aside to ``settings.json.corrupt``
and replaced by defaults: never fatal. A folder that cannot be written (read-only,
or not creatable) is one line too: the viewer starts with the settings it could
read, or defaults, and says that settings will not be saved; saving then raises the
one-line :class:`~envstudio.errors.OutputFileError`. ``ENVSTUDIO_CONFIG_DIR``
overrides the folder (tests, portable installs).
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import platformdirs

from envstudio.errors import OutputFileError
from envstudio.io.atomic import write_text_atomic

APP_NAME = "envmap-studio"


def config_location() -> Path:
    """Folder of the settings file, not created (``envstudio doctor`` reports it)."""
    override = os.environ.get("ENVSTUDIO_CONFIG_DIR")
    return Path(override) if override else Path(platformdirs.user_config_dir(APP_NAME))


def config_dir() -> Path:
    """Folder of the settings file (created if missing).

    Raises
    ------
    OutputFileError
        The folder cannot be created (a read-only file system, no permission).
    """
    folder = config_location()
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputFileError(
            f"{folder}: the settings folder cannot be created ({exc.strerror})"
        ) from None
    return folder


@dataclass
class ViewerSettings:
    """Everything the viewer restores on start.

    Attributes
    ----------
    method : str
        Method shown last.
    method_values : dict
        Method name → {parameter: value}.
    display : dict
        Display parameter values (exposure, tonemap, background).
    scene, environment, mesh : str or None
        Scene name or file, environment file and mesh file last used.
    camera : dict
        Orbit camera azimuth, elevation, distance.
    object_rotation : list of float
        Extra XYZ rotation of the reflectors in degrees.
    turntable : bool
        Turntable animation on.
    turntable_speed : float
        Degrees per second.
    window_size : list of int
        Window width and height.
    imgui_ini : str
        ImGui's panel layout (its .ini text).
    match_glossiness : bool
        The Compare panel's *match glossiness* (split screen, grid, switching methods).
    grid : dict
        The grid view (ui/grid.py, :meth:`GridState.as_settings`): ``on``, the methods
        ``picked`` (empty: all) and the tile fraction's ``scale`` index.
    compare : dict
        The split screen (ui/compare_panel.py, :meth:`CompareState.as_settings`): the
        ``other`` method (None: none), ``split``, ``divider``, ``heat``, ``heat_scale``.
    panels_shown : bool
        The docked panels on show (Tab hides them).
    """

    method: str = "mirror"
    method_values: dict = field(default_factory=dict)
    display: dict = field(default_factory=dict)
    scene: str | None = None
    environment: str | None = None
    mesh: str | None = None
    camera: dict = field(default_factory=dict)
    object_rotation: list = field(default_factory=lambda: [0.0, 0.0, 0.0])
    turntable: bool = False
    turntable_speed: float = 20.0
    window_size: list = field(default_factory=lambda: [1280, 800])
    imgui_ini: str = ""
    match_glossiness: bool = True
    grid: dict = field(default_factory=dict)
    compare: dict = field(default_factory=dict)
    panels_shown: bool = True


def settings_path() -> Path:
    """Path of the settings file (its folder is not created)."""
    return config_location() / "settings.json"


def load_settings() -> tuple[ViewerSettings, str | None]:
    """Read the settings; returns (settings, warning or None).

    A corrupt file is moved to ``settings.json.corrupt`` and defaults are
    returned with a one-line warning naming the file. Where the folder cannot be
    created, or the corrupt file cannot be moved aside (a read-only folder), the
    one-line warning says that settings will not be saved, and the file is left
    as it is.
    """
    path = settings_path()
    try:
        config_dir()
    except OutputFileError as exc:
        return ViewerSettings(), f"{exc}; using defaults, settings will not be saved"
    if not path.exists():
        return ViewerSettings(), None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(data, dict):
            raise ValueError("top level is not an object")
        known = {f.name for f in fields(ViewerSettings)}
        settings = ViewerSettings(**{k: v for k, v in data.items() if k in known})
        _check_types(settings)
        return settings, None
    except (OSError, ValueError, TypeError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        backup = path.with_name(path.name + ".corrupt")
        try:
            os.replace(path, backup)
        except OSError as move:
            return ViewerSettings(), (
                f"{path}: corrupt settings ({reason}); left as it is (it cannot be moved "
                f"aside: {move.strerror}), using defaults, settings will not be saved"
            )
        return (
            ViewerSettings(),
            f"{path}: corrupt settings ({reason}); moved to {backup.name}, using defaults",
        )


def save_settings(settings: ViewerSettings) -> None:
    """Write the settings atomically.

    Raises
    ------
    OutputFileError
        One line: the folder cannot be created or written (read-only), or the disk is full.
    """
    write_text_atomic(config_dir() / "settings.json", json.dumps(asdict(settings), indent=2))


def _check_types(settings: ViewerSettings) -> None:
    defaults = ViewerSettings()
    for f in fields(ViewerSettings):
        value, default = getattr(settings, f.name), getattr(defaults, f.name)
        if default is None:
            if value is not None and not isinstance(value, str):
                raise TypeError(f"{f.name} should be a string")
        elif isinstance(default, (int, float)) and not isinstance(default, bool):
            if not isinstance(value, (int, float)) or isinstance(value, bool):
                raise TypeError(f"{f.name} should be a number")
        elif not isinstance(value, type(default)):
            raise TypeError(f"{f.name} should be {type(default).__name__}")
