"""Snap or play: the camera on a bake's path of views (seed 003's manifold)."""

from __future__ import annotations

import time

import numpy as np

from envstudio.methods.pem.bake.pem_file import PemBake
from envstudio.plugin import ParameterValues
from envstudio.scene.camera import OrbitCamera

__all__ = ["PathSteering", "path_camera"]


def path_camera(view_space: dict, position: float, elevation: float = 0.5) -> OrbitCamera:
    """The camera at fractions ``position`` (azimuth) and ``elevation`` of a bake's path.

    Parameters
    ----------
    view_space
        The bake's ``view_space``: ``azimuths`` and ``elevations`` (degrees, ascending),
        ``distance``, ``target`` (3,) and ``fov_y``.
    position, elevation
        Fractions 0–1 along the azimuths and the elevations, linear between views.
    """
    az = np.asarray(view_space["azimuths"], dtype=np.float64)
    el = np.asarray(view_space["elevations"], dtype=np.float64)
    return OrbitCamera(
        azimuth=float(np.interp(position * (len(az) - 1), np.arange(len(az)), az)),
        elevation=float(np.interp(elevation * (len(el) - 1), np.arange(len(el)), el)),
        distance=float(view_space["distance"]),
        target=np.asarray(view_space["target"], dtype=np.float64),
        fov_y=float(view_space["fov_y"]),
    )


class PathSteering:
    """Puts the camera on the baked path at ``path`` while ``snap`` or ``play`` is on;
    ``play`` advances ``path`` by ``play_speed`` per second of wall time (at most 0.1 s
    a frame), wrapping at 1."""

    def __init__(self):
        self._last_play: float | None = None  # perf_counter of the last frame played

    def steer(self, camera: OrbitCamera, bake: PemBake | None, values: ParameterValues) -> None:
        """Move ``camera`` onto ``bake``'s path (nothing without a bake, snap or play)."""
        if bake is None or not (values["snap"] or values["play"]):
            self._last_play = None
            return
        if values["play"]:
            now = time.perf_counter()
            if self._last_play is not None:
                step = min(now - self._last_play, 0.1) * float(values["play_speed"])
                values["path"] = (float(values["path"]) + step) % 1.0
            self._last_play = now
        on_path = path_camera(
            bake.view_space, float(values["path"]), float(values["path_elevation"])
        )
        camera.azimuth, camera.elevation = on_path.azimuth, on_path.elevation
        camera.distance, camera.target, camera.fov_y = (
            on_path.distance,
            on_path.target,
            on_path.fov_y,
        )
