"""Blending between the sampled views of a PEM (seed 003 §4, "run-time").

The current camera is mapped into the bake's parameter space: its azimuth (and
elevation on a 2D grid) about the bake's target. The nearest two samples of an
arc (four of a grid) are blended with linear (bilinear) weights, so the image
changes continuously as the camera moves; beyond the ends of an arc that does
not close, the end sample takes the whole weight (still continuous); a closed orbit
(issue 31) blends its last azimuth with its first. Unblended
playback (seed 003 §6's table) takes the nearest sample alone.

The PTM (seed 003 §6, Figure 7; issue 31) is a per-texel polynomial in the view
parameters, fitted by least squares to the maps of the views around the camera
(:func:`ptm_blend`): on an arc a quadratic in the azimuth through the four
views about the camera's cell (two bracketing, one beyond each), on a grid
Malzbender et al.'s biquadratic 1, a, e, a², ae, e² through the 4 × 4 views
about its cell (fewer at the ends, the degree cut to what they determine; a closed
orbit's window wraps across 360°, and views that saw no reflector are left out). The
fitted value at the camera is linear in the maps, Σ_j w_j x_j with w the first row
of the fit's pseudo-inverse, so the playback evaluates the polynomial of every
texel by summing the views' lookups with the weights w (of either sign): no
coefficient maps are stored. The window changes at the sampled views, where the
PTM jumps from one fit to the next.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = ["PTM_DEGREE", "ViewBlend", "axis_weights", "camera_angles", "ptm_blend", "view_blend"]

#: Total degree of the PTM's polynomial in the view parameters (Malzbender's biquadratic).
PTM_DEGREE = 2


@dataclass(frozen=True)
class ViewBlend:
    """The samples a frame blends and their weights.

    Attributes
    ----------
    views : tuple of int
        View indices into the bake's views (elevation-major), 1, 2 or 4 of them
        (up to 16 for :func:`ptm_blend`).
    weights : tuple of float
        Their weights, each in [0, 1], summing to 1 (the PTM's: any sign, summing
        to 1).
    position : tuple of float
        The camera's place along the axes in view-index units (azimuth, elevation).
    """

    views: tuple[int, ...]
    weights: tuple[float, ...]
    position: tuple[float, float]


def camera_angles(position: npt.ArrayLike, target: npt.ArrayLike) -> tuple[float, float]:
    """Azimuth and elevation (degrees, OrbitCamera's convention) of an eye about a target.

    Parameters
    ----------
    position, target
        (3,) world-space eye and the bake's target.

    Returns
    -------
    azimuth, elevation : float
        Azimuth in (−180, 180], 0 on +Z, 90 on +X; elevation in [−90, 90].
    """
    d = np.asarray(position, dtype=np.float64) - np.asarray(target, dtype=np.float64)
    azimuth = float(np.degrees(np.arctan2(d[0], d[2])))
    elevation = float(np.degrees(np.arctan2(d[1], np.hypot(d[0], d[2]))))
    return azimuth, elevation


def _unwrap_near(angle: float, samples: npt.NDArray[np.float64]) -> float:
    """``angle`` plus the multiple of 360° that puts it nearest the samples' middle."""
    middle = 0.5 * (samples[0] + samples[-1])
    return float(angle + 360.0 * np.round((middle - angle) / 360.0))


def axis_weights(
    samples: npt.ArrayLike, value: float, periodic: bool = False, closed: bool = False
) -> tuple:
    """Position of ``value`` along increasing ``samples`` as two indices and weights.

    Parameters
    ----------
    samples
        (n,) increasing sample coordinates (degrees).
    value
        The coordinate to place.
    periodic
        Angles: ``value`` is first moved by a multiple of 360° next to the samples.
    closed
        Angles all the way round (implies ``periodic``): past the last sample the
        cell reaches the first, 360° on.

    Returns
    -------
    (i0, i1, w1, u)
        Samples i0 ≤ i1 = min(i0 + 1, n − 1), weight w1 of i1 (1 − w1 of i0), and the
        fractional index u in [0, n − 1] (clamped at the ends). Closed: i1 = (i0 + 1)
        mod n and u in [0, n).
    """
    s = np.asarray(samples, dtype=np.float64).reshape(-1)
    if closed and len(s) > 1:
        value = float(s[0] + np.mod(value - s[0], 360.0))
        u = float(np.interp(value, np.append(s, s[0] + 360.0), np.arange(len(s) + 1.0)))
        i0 = min(int(np.floor(u)), len(s) - 1)
        return i0, (i0 + 1) % len(s), u - i0, u
    if periodic:
        value = _unwrap_near(value, s)
    if len(s) == 1:
        return 0, 0, 0.0, 0.0
    u = float(np.interp(value, s, np.arange(len(s), dtype=np.float64)))
    i0 = min(int(np.floor(u)), len(s) - 2)
    return i0, i0 + 1, u - i0, u


def view_blend(view_space: dict, position: npt.ArrayLike, blend: bool = True) -> ViewBlend:
    """The views and weights for a camera at ``position`` (seed 003 §4, "run-time").

    Parameters
    ----------
    view_space
        ``ViewSpace.describe()`` of the bake (kind, azimuths, elevations, target).
    position
        (3,) camera eye, world space.
    blend
        False: the nearest sample alone (the paper's unblended playback).

    Returns
    -------
    ViewBlend
    """
    azimuths = np.asarray(view_space["azimuths"], dtype=np.float64)
    elevations = np.asarray(view_space["elevations"], dtype=np.float64)
    azimuth, elevation = camera_angles(position, view_space["target"])
    closed = bool(view_space.get("closed", False))
    a0, a1, wa, ua = axis_weights(azimuths, azimuth, periodic=True, closed=closed)
    if view_space["kind"] == "grid" and len(elevations) > 1:
        e0, e1, we, ue = axis_weights(elevations, elevation)
    else:
        e0, e1, we, ue = 0, 0, 0.0, 0.0
    count = len(azimuths)
    corners = [
        (e0 * count + a0, (1 - we) * (1 - wa)),
        (e0 * count + a1, (1 - we) * wa),
        (e1 * count + a0, we * (1 - wa)),
        (e1 * count + a1, we * wa),
    ]
    if not blend:
        nearest = (round(ue) * count + round(ua) % count,)
        return ViewBlend(nearest, (1.0,), (ua, ue))
    if view_space["kind"] != "grid":
        corners = corners[:2]
    return ViewBlend(
        tuple(int(v) for v, _ in corners), tuple(float(w) for _, w in corners), (ua, ue)
    )


def ptm_blend(
    view_space: dict,
    position: npt.ArrayLike,
    degree: int = PTM_DEGREE,
    usable: Callable[[int], bool] | None = None,
) -> ViewBlend:
    """The PTM's views and weights at a camera (module docstring; seed 003 §6, Figure 7).

    Parameters
    ----------
    view_space
        ``ViewSpace.describe()`` of the bake.
    position
        (3,) camera eye, world space.
    degree
        Total degree of the polynomial (per axis at most the window's distinct
        samples − 1, and lower where the views kept do not determine it).
    usable
        View → whether its maps may join the fit (a full orbit's views that saw no
        reflector hold empty maps); None: every view. Where none is usable the
        window is fitted as if all were.

    Returns
    -------
    ViewBlend
        The window's views (at most 16) and weights w with Σ_j w_j x_j the
        least-squares polynomial's value at the camera, for every texel's x.
    """
    azimuths = np.asarray(view_space["azimuths"], dtype=np.float64)
    elevations = np.asarray(view_space["elevations"], dtype=np.float64)
    azimuth, elevation = camera_angles(position, view_space["target"])
    closed = bool(view_space.get("closed", False))
    a0, _, _, ua = axis_weights(azimuths, azimuth, periodic=True, closed=closed)
    ia, ta = _window(len(azimuths), a0, ua, closed)
    if view_space["kind"] == "grid" and len(elevations) > 1:
        e0, _, _, ue = axis_weights(elevations, elevation)
        ie, te = _window(len(elevations), e0, ue)
    else:
        ue, ie, te = 0.0, np.zeros(1, np.int64), np.zeros(1)
    window = [
        (int(e) * len(azimuths) + int(a), t_a, t_e)
        for e, t_e in zip(ie, te, strict=True)
        for a, t_a in zip(ia, ta, strict=True)
    ]
    kept = [w for w in window if usable is None or usable(w[0])] or window
    offsets = np.array([(t_a, t_e) for _, t_a, t_e in kept])
    for total in range(degree, -1, -1):  # the highest degree the views kept determine
        caps = [min(total, len(np.unique(offsets[:, axis])) - 1) for axis in (0, 1)]
        terms = [(p, q) for p in range(caps[0] + 1) for q in range(caps[1] + 1) if p + q <= total]
        rows = np.array([[t_a**p * t_e**q for p, q in terms] for t_a, t_e in offsets])
        if np.linalg.matrix_rank(rows) == len(terms):
            break
    weights = np.linalg.pinv(rows)[0]  # the constant term: the value at the camera
    return ViewBlend(tuple(v for v, _, _ in kept), tuple(float(w) for w in weights), (ua, ue))


def _window(count: int, i0: int, u: float, closed: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the views about cell [i0, i0 + 1] of one axis and their offsets from u.

    Closed (azimuths all the way round, at least 4): the 4 views i0 − 1 … i0 + 2
    taken modulo ``count``, their offsets unwrapped.
    """
    if closed and count >= 4:
        idx = np.arange(i0 - 1, i0 + 3)
        return idx % count, idx - u
    idx = np.arange(max(0, i0 - 1), min(count - 1, i0 + 2) + 1)
    return idx, idx - u
