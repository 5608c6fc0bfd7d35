"""The parameter space of a PEM bake: viewpoints about the reflector (seed 003 §3, §6).

Seed 003 §6 ray traces "a 1D viewspace partially circling the teapot at 1° per
view sample", 100 views. :func:`arc_views` is that default: N cameras of
:class:`~envstudio.scene.camera.OrbitCamera` at successive azimuths ``step``
degrees apart, at one elevation and distance about one target. :func:`grid_views`
adds elevation as a second axis (a 2D view grid); :func:`orbit_views` is the grid
that covers every camera the viewer's orbit reaches (issue 31: azimuth closed
over 360°, elevations to the orbit's ±89° limit). Angles follow OrbitCamera:
degrees, azimuth 0 / elevation 0 on +Z looking down −Z, +Y up.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from envstudio.scene.camera import OrbitCamera

#: The elevation limit of :meth:`OrbitCamera.orbit`, degrees.
ELEVATION_LIMIT = 89.0


@dataclass
class ViewSpace:
    """A sampled view space: a grid of orbit angles about one target.

    Attributes
    ----------
    azimuths : (n_az,) float64
        Azimuths in degrees, in sampling order (not wrapped to [0, 360)).
    elevations : (n_el,) float64
        Elevations in degrees; one entry for a 1D arc.
    distance : float
        Camera distance from ``target``, scene units.
    target : (3,) float64
        Point the cameras look at (world space).
    fov_y : float
        Vertical field of view, degrees.
    kind : str
        ``"arc"`` (1D, along azimuth) or ``"grid"`` (2D, elevation × azimuth).
    closed : bool
        The azimuths go all the way round: the last view's neighbour is the first
        (:func:`orbit_views`).
    """

    azimuths: npt.NDArray[np.float64]
    elevations: npt.NDArray[np.float64]
    distance: float
    target: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    fov_y: float = 45.0
    kind: str = "arc"
    closed: bool = False

    @property
    def shape(self) -> tuple[int, ...]:
        """(n,) for an arc, (n_el, n_az) for a grid."""
        if self.kind == "arc":
            return (len(self.azimuths),)
        return (len(self.elevations), len(self.azimuths))

    def __len__(self) -> int:
        return len(self.azimuths) * len(self.elevations)

    def cameras(self) -> list[OrbitCamera]:
        """One camera per view, elevation-major (row-major over :attr:`shape`)."""
        return [
            OrbitCamera(
                azimuth=float(az),
                elevation=float(el),
                distance=self.distance,
                target=self.target.copy(),
                fov_y=self.fov_y,
            )
            for el in self.elevations
            for az in self.azimuths
        ]

    def describe(self) -> dict:
        """A plain-data description (for the bake's file and messages).

        ``closed`` is present only for a closed orbit, so that the description (and
        the key) of every bake made before it is unchanged.
        """
        closed = {"closed": True} if self.closed else {}
        return {
            **closed,
            "kind": self.kind,
            "azimuths": [float(a) for a in self.azimuths],
            "elevations": [float(e) for e in self.elevations],
            "distance": float(self.distance),
            "target": [float(t) for t in self.target],
            "fov_y": float(self.fov_y),
        }


def _axis(count: int, step: float, start: float, name: str, period: float | None) -> np.ndarray:
    if int(count) != count or count < 1:
        raise ValueError(f"{name}: view count {count!r}, expected a whole number ≥ 1")
    if not np.isfinite(step) or (count > 1 and step <= 0.0):
        raise ValueError(f"{name}: step {step!r}°, expected a positive number of degrees")
    if period is not None and count > 1 and (count - 1) * step >= period - 1e-9:
        raise ValueError(
            f"{name}: {count} views at {step}° span {(count - 1) * step:g}°, "
            f"so views would coincide (at most {period:g}°)"
        )
    return float(start) + float(step) * np.arange(int(count), dtype=np.float64)


def arc_views(
    base: OrbitCamera, count: int = 100, step: float = 1.0, start: float | None = None
) -> ViewSpace:
    """The default 1D parameter space: ``count`` views ``step`` degrees apart in azimuth.

    Parameters
    ----------
    base
        Camera whose elevation, distance, target and field of view the views share
        (a scene's default camera).
    count
        N, number of views (seed 003 §6: 100).
    step
        Azimuth increment between successive views, degrees (seed 003 §6: 1°). At
        elevation 0 this is also the angle between successive view directions.
    start
        Azimuth of the first view, degrees; default ``base.azimuth``.

    Returns
    -------
    ViewSpace
        ``kind="arc"``, shape (count,).

    Raises
    ------
    ValueError
        A count below 1, a non-positive step, or an arc of 360° or more (views coincide).
    """
    az = _axis(count, step, base.azimuth if start is None else start, "arc", 360.0)
    return ViewSpace(
        az, np.array([base.elevation], dtype=np.float64), base.distance, base.target, base.fov_y
    )


def grid_views(
    base: OrbitCamera,
    azimuth_count: int,
    azimuth_step: float,
    elevation_count: int,
    elevation_step: float,
    start: tuple[float, float] | None = None,
) -> ViewSpace:
    """A 2D parameter space: elevation × azimuth grid of views.

    Parameters
    ----------
    base
        Camera whose distance, target and field of view the views share.
    azimuth_count, azimuth_step
        Views along azimuth and their spacing in degrees.
    elevation_count, elevation_step
        Views along elevation and their spacing in degrees.
    start
        (azimuth, elevation) of the first view in degrees; default the base camera's.

    Returns
    -------
    ViewSpace
        ``kind="grid"``, shape (elevation_count, azimuth_count).

    Raises
    ------
    ValueError
        As :func:`arc_views` per axis, or elevations beyond ±89°.
    """
    az0, el0 = (base.azimuth, base.elevation) if start is None else start
    az = _axis(azimuth_count, azimuth_step, az0, "grid azimuth", 360.0)
    el = _axis(elevation_count, elevation_step, el0, "grid elevation", None)
    if np.abs(el).max() > ELEVATION_LIMIT:
        raise ValueError(f"grid elevation: {el[0]:g}°…{el[-1]:g}° leaves ±{ELEVATION_LIMIT:g}°")
    return ViewSpace(az, el, base.distance, base.target, base.fov_y, kind="grid")


def orbit_views(base: OrbitCamera, azimuth_step: float, elevation_step: float) -> ViewSpace:
    """The grid that covers every orbit camera at the base camera's distance (issue 31).

    Azimuths go all the way round from the base camera's, ``azimuth_step`` apart
    (the last cell closes on the first); elevations are the base camera's plus
    and minus whole steps, and the orbit's limits ±89° (:data:`ELEVATION_LIMIT`)
    as the first and last rows (the cells next to them are narrower), so the base
    camera is a sample and every orbit camera lies inside the grid.

    Parameters
    ----------
    base
        The scene's camera: its azimuth, elevation, distance, target and field of
        view.
    azimuth_step, elevation_step
        Spacing in degrees; ``azimuth_step`` must divide 360.

    Returns
    -------
    ViewSpace
        ``kind="grid"``, ``closed=True``, shape (n_el, 360 / azimuth_step).

    Raises
    ------
    ValueError
        A step that is not positive, or an azimuth step that does not divide 360°.
    """
    for name, step in (("azimuth", azimuth_step), ("elevation", elevation_step)):
        if not (np.isfinite(step) and 0.0 < step <= 180.0):
            raise ValueError(f"orbit {name} step {step!r}°: expected degrees in (0, 180]")
    count = 360.0 / azimuth_step
    if abs(count - round(count)) > 1e-6:
        raise ValueError(f"orbit azimuth step {azimuth_step:g}°: expected a divisor of 360°")
    azimuths = float(base.azimuth) + azimuth_step * np.arange(round(count), dtype=np.float64)
    below = np.floor((float(base.elevation) + ELEVATION_LIMIT) / elevation_step + 1e-9)
    above = np.floor((ELEVATION_LIMIT - float(base.elevation)) / elevation_step + 1e-9)
    steps = np.arange(-int(below), int(above) + 1, dtype=np.float64)
    elevations = float(base.elevation) + elevation_step * steps
    if elevations[0] > -ELEVATION_LIMIT + 1e-6:  # the last row closer: the limit itself
        elevations = np.concatenate([[-ELEVATION_LIMIT], elevations])
    if elevations[-1] < ELEVATION_LIMIT - 1e-6:
        elevations = np.concatenate([elevations, [ELEVATION_LIMIT]])
    return ViewSpace(
        azimuths, elevations, base.distance, base.target, base.fov_y, kind="grid", closed=True
    )


def uncovered(space: ViewSpace | dict, cameras: list[OrbitCamera]) -> list[OrbitCamera]:
    """The cameras outside a view space's samples, which playback clamps to its edge.

    A camera is outside when its elevation is beyond the first or last sampled
    elevation or, unless the azimuths are closed, its azimuth beyond the ends of the
    arc (by more than 10⁻⁶°).

    Parameters
    ----------
    space
        The view space, or its :meth:`ViewSpace.describe`.
    cameras
        Orbit cameras about the same target.

    Returns
    -------
    list of OrbitCamera
        Those outside, in the given order.
    """
    described = space.describe() if isinstance(space, ViewSpace) else space
    az = np.asarray(described["azimuths"], dtype=np.float64)
    el = np.asarray(described["elevations"], dtype=np.float64)
    out = []
    for camera in cameras:
        outside = not (el.min() - 1e-6 <= camera.elevation <= el.max() + 1e-6)
        if not described.get("closed", False):
            middle = 0.5 * (az[0] + az[-1])
            a = float(camera.azimuth) + 360.0 * np.round((middle - camera.azimuth) / 360.0)
            outside |= not (az.min() - 1e-6 <= a <= az.max() + 1e-6)
        if outside:
            out.append(camera)
    return out
