"""Viewer settings persisted between runs in the user config directory.

Stored as JSON (``settings.json``), written atomically. A file that cannot be
read or parsed is reported in one line, moved aside to ``settings.json.corrupt``
and replaced by defaults: never fatal. ``ENVSTUDIO_CONFIG_DIR`` overrides the
folder (tests, portable installs).
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import platformdirs

from envstudio.io.atomic import write_text_atomic

APP_NAME = "envmap-studio"


def config_location() -> Path:
    """Folder of the settings file, not created (``envstudio doctor`` reports it)."""
    override = os.environ.get("ENVSTUDIO_CONFIG_DIR")
    return Path(override) if override else Path(platformdirs.user_config_dir(APP_NAME))


def config_dir() -> Path:
    """Folder of the settings file (created if missing)."""
    folder = config_location()
    folder.mkdir(parents=True, exist_ok=True)
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
    """Path of the settings file."""
    return config_dir() / "settings.json"


def load_settings() -> tuple[ViewerSettings, str | None]:
    """Read the settings; returns (settings, warning or None).

    A corrupt file is moved to ``settings.json.corrupt`` and defaults are
    returned with a one-line warning naming the file.
    """
    path = settings_path()
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
        backup = path.with_name(path.name + ".corrupt")
        os.replace(path, backup)
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        return (
            ViewerSettings(),
            f"{path}: corrupt settings ({reason}); moved to {backup.name}, using defaults",
        )


def save_settings(settings: ViewerSettings) -> None:
    """Write the settings atomically."""
    write_text_atomic(settings_path(), json.dumps(asdict(settings), indent=2))


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
