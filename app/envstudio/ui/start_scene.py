"""The scene the viewer opens with: the command line's, else the one last shown."""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

from envstudio.errors import UserError
from envstudio.io.meshes import load_mesh
from envstudio.io.scene_file import shipped_scenes
from envstudio.io.scene_setup import DEFAULT_SCENE, build_scene, replace_reflector
from envstudio.scene.graph import Node, Scene
from envstudio.ui.settings import ViewerSettings


@dataclass
class StartScene:
    """The scene the viewer opens with and where it came from.

    Attributes
    ----------
    scene : Scene
        Loaded scene (environment and reflector replacements applied).
    spec : str
        Shipped scene name or absolute scene file path.
    reflectors : list of Node
        The scene file's own reflectors.
    environment, mesh : str or None
        Replacement files.
    """

    scene: Scene
    spec: str
    reflectors: list[Node]
    environment: str | None
    mesh: str | None


def start_scene(
    args: argparse.Namespace, settings: ViewerSettings, warnings: list[str]
) -> StartScene:
    """The scene from the command line, else the one last shown (falling back to the default).

    Parameters
    ----------
    args
        The ``view`` options: scene, env, mesh, max_env_width.
    settings
        Settings read at start (the scene, environment and mesh last shown).
    warnings
        Receives a line when the last scene cannot be restored.

    Raises
    ------
    UserError
        A scene, environment or mesh named on the command line cannot be loaded.
    """
    given = (args.scene, args.env, args.mesh)
    if args.scene is None:
        wanted = (settings.scene, args.env or settings.environment, args.mesh or settings.mesh)
    else:
        wanted = given
    try:
        return _load_start(*wanted, args.max_env_width)
    except UserError as exc:
        if wanted == given:
            raise
        warnings.append(f"cannot restore the last scene ({exc}); using the defaults")
        return _load_start(*given, args.max_env_width)


def _load_start(
    spec: str | None, environment: str | None, mesh: str | None, max_env_width: int | None
) -> StartScene:
    spec = spec or DEFAULT_SCENE
    scene = build_scene(spec, environment, None, max_env_width)
    reflectors = scene.reflectors()
    if mesh:
        scene.nodes = replace_reflector(scene, load_mesh(mesh).fitted(1.0))
    if spec not in shipped_scenes():
        spec = str(Path(spec).resolve())
    return StartScene(scene, spec, reflectors, environment, mesh)
