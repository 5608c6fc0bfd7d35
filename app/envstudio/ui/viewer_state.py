"""The viewer's state restored from, and saved into, the settings file (:mod:`.settings`).

Restored on start: the display, the camera (for the scene it was saved with),
the reflectors' rotation, the turntable, glossiness matching, the grid and the
split screen (unless the command line names them). Each method's saved parameter
values are applied when the method is first used (:mod:`.method_choice`).
A saved value that is malformed is skipped with a message; an unknown name is
skipped silently. Saved when the viewer ends normally, with the window size,
the panel layout and whether the panels are shown.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterable

import numpy as np

from envstudio.core.parameters import ParameterValues
from envstudio.engine.session import RenderSession
from envstudio.errors import ParameterError, UserError
from envstudio.scene.camera import OrbitCamera
from envstudio.ui.compare_panel import CompareState
from envstudio.ui.grid import GridState
from envstudio.ui.scene_control import SceneControl
from envstudio.ui.settings import ViewerSettings, save_settings


def restore_values(values: ParameterValues, saved: object) -> list[str]:
    """Assign the saved ``{name: value}`` entries that are declared and valid.

    Returns
    -------
    list of str
        One message per rejected value (unknown names are skipped silently:
        a parameter may have been renamed since the settings were written).
    """
    if not isinstance(saved, dict):
        return [f"expected a table of parameter values, got {type(saved).__name__}"]
    problems = []
    for name, value in saved.items():
        if name in values:
            try:
                values[name] = value
            except ParameterError as exc:
                problems.append(str(exc))
    return problems


def restore_camera(camera: OrbitCamera, saved: dict) -> list[str]:
    """Set the saved azimuth, elevation, distance and target; returns rejected entries."""
    problems = []
    for key in ("azimuth", "elevation", "distance"):
        value = saved.get(key)
        if _is_number(value):
            setattr(camera, key, float(value))
        elif key in saved:
            problems.append(f"camera.{key} = {value!r}, expected a number")
    target = saved.get("target")
    if isinstance(target, list) and len(target) == 3 and all(_is_number(v) for v in target):
        camera.target = np.array(target, dtype=np.float64)
    elif "target" in saved:
        problems.append(f"camera.target = {target!r}, expected [x, y, z]")
    camera.orbit(0.0, 0.0)
    camera.zoom(1.0)
    return problems


def restore_viewer_state(
    settings: ViewerSettings,
    session: RenderSession,
    control: SceneControl,
    compare: CompareState,
    grid: GridState,
    methods: list[str],
    *,
    restore_grid: bool,
    restore_split: bool,
    same_scene: bool,
) -> list[str]:
    """Apply the saved display, matching, grid, split, camera, rotation and turntable.

    Parameters
    ----------
    settings
        Settings read at start.
    session, control, compare, grid
        What they are restored into.
    methods
        Names of the methods available (a saved grid or split of others is dropped).
    restore_grid, restore_split
        False where the command line named the grid or the split's other method.
    same_scene
        The viewer opens the scene the camera was saved with.

    Returns
    -------
    list of str
        One ``settings: ...`` message per rejected value.
    """
    problems = restore_values(session.renderer.display, settings.display)
    compare.match = settings.match_glossiness
    if restore_grid:
        problems += grid.restore(settings.grid, methods)
    if restore_split:
        problems += compare.restore(settings.compare, methods)
    if same_scene:
        problems += restore_camera(session.camera, settings.camera)
    rotation = settings.object_rotation
    if len(rotation) == 3 and all(_is_number(v) for v in rotation):
        control.set_rotation(rotation)
    else:
        problems.append(f"object_rotation = {rotation!r}, expected [x, y, z] degrees")
    control.turntable = settings.turntable
    if _is_number(settings.turntable_speed):
        control.turntable_speed = float(settings.turntable_speed)
    else:
        problems.append(f"turntable_speed = {settings.turntable_speed!r}, expected deg/s")
    return [f"settings: {problem}" for problem in problems]


def save_viewer_state(
    settings: ViewerSettings,
    session: RenderSession,
    control: SceneControl,
    compare: CompareState,
    grid: GridState,
    *,
    method: str,
    used_methods: Iterable[str],
    window_size: tuple[int, int],
    imgui_ini: str,
    panels_shown: bool,
) -> None:
    """Store the viewer's state in ``settings`` and write them; a failure is a warning.

    Parameters
    ----------
    settings
        Settings read at start; updated in place.
    session, control, compare, grid
        What is saved.
    method
        The method on show.
    used_methods
        Methods whose parameter values are saved (those used this run; the
        others keep what was read).
    window_size
        The window's width and height in points.
    imgui_ini
        ImGui's panel layout.
    panels_shown
        The panels are on show (Tab hides them).
    """
    settings.method = method
    for name in used_methods:
        settings.method_values[name] = session.method(name).values.as_dict()
    settings.display = session.renderer.display.as_dict()
    settings.scene = control.scene_spec
    env, mesh = control.environment_path, control.mesh_path
    settings.environment = str(env) if env else None
    settings.mesh = str(mesh) if mesh else None
    camera = session.camera
    settings.camera = {
        "azimuth": camera.azimuth,
        "elevation": camera.elevation,
        "distance": camera.distance,
        "target": [float(v) for v in camera.target],
    }
    settings.object_rotation = list(control.rotation)
    settings.turntable = control.turntable
    settings.turntable_speed = control.turntable_speed
    settings.window_size = list(window_size)
    settings.imgui_ini = imgui_ini
    settings.match_glossiness = compare.match
    settings.grid = grid.as_settings()
    settings.compare = compare.as_settings()
    settings.panels_shown = panels_shown
    try:
        save_settings(settings)
    except (OSError, UserError) as exc:
        print(f"envstudio: warning: settings not saved ({exc})", file=sys.stderr)


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
