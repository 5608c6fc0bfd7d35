"""Mouse gestures on the orbit camera: left-drag orbits, right-drag or shift+left pans, wheel zooms.

A drag belongs to the gesture chosen when its button went down; a press that
ImGui claimed (over a panel) starts no gesture, so dragging a slider never
turns the camera, and a camera drag that crosses a panel keeps turning it.
"""

from __future__ import annotations

import math
from enum import Enum

from envstudio.scene.camera import OrbitCamera

ORBIT_DEGREES_PER_POINT = 0.4
"""Camera rotation per point of mouse travel."""

ZOOM_PER_NOTCH = 0.9
"""Distance factor per wheel notch towards the target."""


class Gesture(Enum):
    """What the current drag does."""

    NONE = "none"
    ORBIT = "orbit"
    PAN = "pan"


class CameraControl:
    """Turns mouse events into :class:`OrbitCamera` moves.

    Parameters
    ----------
    left, right
        The window backend's button numbers (``wnd.mouse.left``, ``wnd.mouse.right``).
    """

    def __init__(self, left: int, right: int):
        self._left = left
        self._right = right
        self.gesture = Gesture.NONE

    def press(self, button: int, shift: bool, captured: bool) -> None:
        """Start a gesture for ``button`` unless ImGui ``captured`` the press."""
        if captured:
            self.gesture = Gesture.NONE
        elif button == self._right or (button == self._left and shift):
            self.gesture = Gesture.PAN
        elif button == self._left:
            self.gesture = Gesture.ORBIT

    def release(self) -> None:
        """End the current gesture."""
        self.gesture = Gesture.NONE

    def drag(self, camera: OrbitCamera, dx: float, dy: float, height: float) -> None:
        """Apply a cursor move of (dx, dy) points in a view ``height`` points tall.

        Orbiting grabs the object (drag right: its front turns right); panning
        moves the target so that points at the target's depth follow the cursor.
        """
        if self.gesture is Gesture.ORBIT:
            camera.orbit(-dx * ORBIT_DEGREES_PER_POINT, dy * ORBIT_DEGREES_PER_POINT)
        elif self.gesture is Gesture.PAN and height > 0:
            # The view is 2·tan(fov/2) distances tall at the target; pan() takes distances.
            scale = 2.0 * math.tan(math.radians(camera.fov_y) / 2.0) / height
            camera.pan(-dx * scale, dy * scale)

    @staticmethod
    def scroll(camera: OrbitCamera, notches: float) -> None:
        """Zoom: positive ``notches`` (wheel up) move towards the target."""
        camera.zoom(ZOOM_PER_NOTCH**notches)
