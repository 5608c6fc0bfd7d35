"""4×4 transforms in the OpenGL convention (column vectors, right-handed, view looks down −Z).

Matrices are float32 (4, 4) arrays meant to multiply column vectors; upload
them to GLSL with ``matrix.T.tobytes()`` (GLSL is column-major).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

Mat4 = npt.NDArray[np.float32]


def translation(offset: npt.ArrayLike) -> Mat4:
    """Translation by ``offset`` (3,)."""
    m = np.eye(4, dtype=np.float32)
    m[:3, 3] = np.asarray(offset, dtype=np.float32)
    return m


def scaling(factor: float | npt.ArrayLike) -> Mat4:
    """Uniform (scalar) or per-axis (3,) scale."""
    m = np.eye(4, dtype=np.float32)
    m[[0, 1, 2], [0, 1, 2]] = np.broadcast_to(np.asarray(factor, dtype=np.float32), (3,))
    return m


def rotation_xyz(degrees: npt.ArrayLike) -> Mat4:
    """Rotation about X, then Y, then Z by the angles (3,) in degrees: R = Rz · Ry · Rx."""
    ax, ay, az = np.radians(np.asarray(degrees, dtype=np.float64))
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    m = np.eye(4, dtype=np.float32)
    m[:3, :3] = rz @ ry @ rx
    return m


def look_at(eye: npt.ArrayLike, target: npt.ArrayLike, up: npt.ArrayLike = (0, 1, 0)) -> Mat4:
    """View matrix (world → view) of a camera at ``eye`` looking at ``target``."""
    eye = np.asarray(eye, dtype=np.float64)
    forward = np.asarray(target, dtype=np.float64) - eye
    forward /= np.linalg.norm(forward)
    side = np.cross(forward, np.asarray(up, dtype=np.float64))
    if np.linalg.norm(side) < 1e-8:
        side = np.cross(forward, (0.0, 0.0, 1.0))
    side /= np.linalg.norm(side)
    true_up = np.cross(side, forward)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = side, true_up, -forward
    m[:3, 3] = -m[:3, :3] @ eye
    return m.astype(np.float32)


def perspective(fov_y_degrees: float, aspect: float, near: float, far: float) -> Mat4:
    """OpenGL perspective projection (clip z in [−w, w])."""
    f = 1.0 / np.tan(np.radians(fov_y_degrees) / 2.0)
    m = np.zeros((4, 4), dtype=np.float32)
    m[0, 0] = f / aspect
    m[1, 1] = f
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2.0 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


def normal_matrix(model: Mat4) -> npt.NDArray[np.float32]:
    """(3, 3) inverse transpose of the model matrix's linear part, for normals."""
    return np.linalg.inv(model[:3, :3].astype(np.float64)).T.astype(np.float32)
