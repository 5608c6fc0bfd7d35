"""Is a bake for this scene? (issue 19, "Bad input": refused in one line.)"""

from __future__ import annotations

from pathlib import Path

from envstudio.methods.pem.bake.hull import mesh_check
from envstudio.methods.pem.bake.pem_file import PemBake
from envstudio.plugin import InputFileError
from envstudio.scene.graph import Scene

__all__ = ["check_bake_for_scene"]


def check_bake_for_scene(bake: PemBake, scene: Scene, path: Path) -> None:
    """Refuse a bake of another scene, other reflector parts or another mesh.

    Parameters
    ----------
    bake
        A loaded, checksum-verified bake.
    scene
        The scene on show.
    path
        The bake's file, for the message.

    Raises
    ------
    InputFileError
        One line naming the file, what it holds and what the scene expects.
    """
    parts = [node.name for node in scene.reflectors()]
    if bake.scene != scene.name:
        raise InputFileError(
            f"{path}: a bake of scene {bake.scene!r}, expected one of {scene.name!r}"
        )
    if list(bake.parts) != parts:
        raise InputFileError(
            f"{path}: reflector parts {', '.join(bake.parts)}, expected {', '.join(parts)}"
        )
    checks = list(getattr(bake, "mesh_checks", [])) or [None] * len(parts)
    if len(checks) != len(parts) or len(bake.hull) != len(parts):
        raise InputFileError(
            f"{path}: {len(checks)} mesh checks and {len(bake.hull)} hull masks for "
            f"{len(parts)} parts: re-bake"
        )
    for node, hull, baked in zip(scene.reflectors(), bake.hull, checks, strict=True):
        here = mesh_check(node)
        if len(hull) != here["triangles"]:
            raise InputFileError(
                f"{path}: part {node.name!r} was baked with {len(hull)} triangles, "
                f"the scene's mesh has {here['triangles']}: re-bake"
            )
        if baked is None:
            continue
        if (baked["vertices"], baked["triangles"]) != (here["vertices"], here["triangles"]):
            raise InputFileError(
                f"{path}: part {node.name!r} was baked with {baked['vertices']} vertices and "
                f"{baked['triangles']} triangles, the scene's mesh has {here['vertices']} and "
                f"{here['triangles']}: re-bake"
            )
        if baked["sha256"] != here["sha256"]:
            raise InputFileError(
                f"{path}: part {node.name!r} was baked from another mesh or placement "
                "(mesh checksum differs): re-bake"
            )
