"""The proxy volume of a parallax-corrected cube map (plain data, NumPy).

Lagarde and Zanuttini ("Local image-based lighting with parallax-corrected cubemaps",
SIGGRAPH 2012 talk) stand a simple volume for the geometry a cube map was captured
of: a reflection ray from a shaded point P along r is intersected with it, and the
cube captured at the probe point C is looked up towards the hit, X − C, instead of
along r. Their proxies are boxes (and, in the course notes that followed, spheres);
here a world-space axis-aligned box or a sphere, declared in the scene file's
``[proxy]`` table (io/scene_file.py) and carried on :class:`~envstudio.scene.graph.Scene`.

The probe C is the point the cube map is captured from: ``probe`` when the scene
declares one, otherwise the reflectors' centre, where the static environment is
captured (shading/gpu_scene.py). It must lie inside the proxy: the rays are cast from
inside, and a probe outside would look up the proxy's far side.

The GLSL twin is shaders/parallax/proxy.glsl; tests/test_parallax_gl.py holds the two
against each other.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

Vector3 = tuple[float, float, float]

__all__ = ["BoxProxy", "Proxy", "SphereProxy", "Vector3"]


def _vector(value) -> npt.NDArray[np.float64]:
    return np.asarray(value, dtype=np.float64)


@dataclass(frozen=True)
class BoxProxy:
    """An axis-aligned box from ``minimum`` to ``maximum`` (world space, each axis min < max).

    Attributes
    ----------
    minimum, maximum : (3,) tuple of float
        Opposite corners.
    probe : (3,) tuple of float or None
        The capture point, None for the reflectors' centre.
    """

    minimum: Vector3
    maximum: Vector3
    probe: Vector3 | None = None

    shape = "box"

    def contains(self, point: npt.ArrayLike) -> bool:
        """True when ``point`` (3,) lies strictly inside the box."""
        p = _vector(point)
        return bool(np.all(p > _vector(self.minimum)) and np.all(p < _vector(self.maximum)))

    def exit_distance(self, origins: npt.ArrayLike, directions: npt.ArrayLike) -> np.ndarray:
        """t at which the rays o + t·d (..., 3) leave the box (Lagarde's eq. for a box).

        For each axis the slab plane ahead of the ray, (max − o)/d where d > 0 and
        (min − o)/d where d < 0; the nearest of the three. From inside the box t > 0.

        Returns
        -------
        (...,) float64
            t, +inf where no plane lies ahead (d = 0).
        """
        o, d = _vector(origins), _vector(directions)
        bound = np.where(d > 0, _vector(self.maximum), _vector(self.minimum)) - o
        safe = np.where(d != 0, d, 1.0)
        return np.where(d != 0, bound / safe, np.inf).min(axis=-1)

    def describe(self) -> str:
        """``box [x, y, z]..[x, y, z]``."""
        return f"box {_format(self.minimum)}..{_format(self.maximum)}"


@dataclass(frozen=True)
class SphereProxy:
    """A sphere of ``radius`` about ``centre`` (world space).

    Attributes
    ----------
    centre : (3,) tuple of float
    radius : float
        > 0.
    probe : (3,) tuple of float or None
        The capture point, None for the reflectors' centre.
    """

    centre: Vector3
    radius: float
    probe: Vector3 | None = None

    shape = "sphere"

    def contains(self, point: npt.ArrayLike) -> bool:
        """True when ``point`` (3,) lies strictly inside the sphere."""
        return bool(np.linalg.norm(_vector(point) - _vector(self.centre)) < self.radius)

    def exit_distance(self, origins: npt.ArrayLike, directions: npt.ArrayLike) -> np.ndarray:
        """t at which the rays o + t·d (..., 3, d of unit length) leave the sphere.

        The larger root of |o + t d − c|² = R², t = −b + √(b² − k) with b = d·(o − c),
        k = |o − c|² − R² (< 0 inside, so the root is real and positive).

        Returns
        -------
        (...,) float64
            t, NaN where the ray misses the sphere (from outside).
        """
        o = _vector(origins) - _vector(self.centre)
        d = _vector(directions)
        b = np.sum(o * d, axis=-1)
        k = np.sum(o * o, axis=-1) - self.radius**2
        disc = b * b - k
        return np.where(disc >= 0, -b + np.sqrt(np.maximum(disc, 0.0)), np.nan)

    def describe(self) -> str:
        """``sphere [x, y, z] radius R``."""
        return f"sphere {_format(self.centre)} radius {self.radius:g}"


#: What a scene may declare as its proxy.
Proxy = BoxProxy | SphereProxy


def _format(vector) -> str:
    return "[" + ", ".join(f"{float(v):g}" for v in vector) + "]"
