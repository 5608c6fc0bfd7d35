"""Orbit camera: azimuth, elevation and distance about a target (plain data)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from envstudio.core.transforms import Mat4, look_at, perspective


@dataclass
class OrbitCamera:
    """A camera on a sphere around ``target``; +Y up.

    Azimuth 0 and elevation 0 put the camera on +Z looking down −Z (the centre
    of the lat-long map is behind the object). Angles in degrees, distance in
    scene units.
    """

    azimuth: float = 0.0
    elevation: float = 0.0
    distance: float = 3.0
    target: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    fov_y: float = 45.0
    near: float = 0.05
    far: float = 100.0

    def __post_init__(self):
        self.target = np.asarray(self.target, dtype=np.float64).reshape(3)
        self._home = (self.azimuth, self.elevation, self.distance, self.target.copy())

    @property
    def position(self) -> npt.NDArray[np.float64]:
        """(3,) eye position in world space."""
        az, el = np.radians(self.azimuth), np.radians(self.elevation)
        offset = np.array([np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)])
        return self.target + self.distance * offset

    def view_matrix(self) -> Mat4:
        """World → view matrix."""
        return look_at(self.position, self.target)

    def projection_matrix(self, aspect: float) -> Mat4:
        """Perspective projection for a viewport of width/height ``aspect``."""
        return perspective(self.fov_y, aspect, self.near, self.far)

    def orbit(self, d_azimuth: float, d_elevation: float) -> None:
        """Rotate about the target by angle increments in degrees (elevation clamped to ±89°)."""
        self.azimuth = (self.azimuth + d_azimuth) % 360.0
        self.elevation = float(np.clip(self.elevation + d_elevation, -89.0, 89.0))

    def zoom(self, factor: float) -> None:
        """Multiply the distance by ``factor`` (kept within [near·2, far/2])."""
        self.distance = float(np.clip(self.distance * factor, self.near * 2, self.far / 2))

    def pan(self, dx: float, dy: float) -> None:
        """Move the target in the view plane by fractions of the distance."""
        view = self.view_matrix()
        right, up = view[0, :3].astype(np.float64), view[1, :3].astype(np.float64)
        self.target = self.target + (right * dx + up * dy) * self.distance

    def reset(self) -> None:
        """Return to the pose the camera was created with."""
        self.azimuth, self.elevation, self.distance, target = self._home
        self.target = target.copy()
