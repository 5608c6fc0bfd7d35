"""Distortion of a paraboloid-space kernel mapped back to the sphere (seed 004 §5.2, Fig. 3).

The convolution of §5.2 uses one circular kernel of radius r (units of the face's
disc radius: "r = 1 is half the width of the parabolic map") everywhere in a face.
Projected back to the sphere, the kernel centred at distance d from the face's
centre covers a region whose border lies at angular distances α(ψ) from the
kernel's centre direction c, ψ the azimuth about c. Figure 3 plots how much these
distances "deviate from a constant radius", the maximum deviation being the error.

The paraboloid face (s, t) = (x, y) / (1 + z) (core.paraboloid) is the stereographic
projection from the pole −Z, which is conformal and maps circles to circles. So the
projected kernel is an exact spherical circle of angular radius ρ; only its centre
moves away from c (the paraboloid's scale dθ/ds = 2 / (1 + s²) falls outwards, so the
inner half of the kernel covers more angle than the outer half). Along the radius
through the face's centre, where θ = 2 atan s, the border lies at::

    α_in  = 2 (atan d − atan(d − r))       towards the face's centre (the largest)
    α_out = 2 (atan(d + r) − atan d)       towards the rim (the smallest)

and every other α(ψ) lies between them. With ρ = (α_in + α_out) / 2 the distances
span ρ (1 ± e), the error::

    e(r, d) = (α_in − α_out) / (α_in + α_out)
            = (2 atan d − atan(d + r) − atan(d − r)) / (atan(d + r) − atan(d − r))

For small r, e ≈ r d / (1 + d²): 0 at the centre, largest at the rim, where
e(r, 1) = atan(r² / 2) / atan(2r / (2 − r²)) ≈ r / 2. The largest kernel of §5.2's
table, the large one of N = 10 (r_l = 0.506), gives 24.2 % there: the paper's
"the distortion goes up to 25 % for large radii". :func:`kernel_distortion` measures
e by projecting sampled border points with core.paraboloid; :func:`analytic_distortion`
is the closed form above.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.core import paraboloid

__all__ = ["analytic_distortion", "border_distances", "kernel_distortion"]


def _centre_and_border(
    radius: float, distance: float, samples: int
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Sphere directions of the kernel's centre (3,) and of its border (samples, 3).

    The kernel lies on the front face about (s, t) = (d, 0); border points past the
    rim continue onto the back hemisphere, as the map's border does.
    """
    phi = 2.0 * np.pi * np.arange(samples) / samples
    st = np.stack([distance + radius * np.cos(phi), radius * np.sin(phi)], axis=-1)
    points = np.concatenate([[[distance, 0.0]], st])
    # A face of size 1 without border: uv = 0.5 + 0.5 (s, t).
    directions = paraboloid.uv_to_direction(0, 0.5 + 0.5 * points, 1, 0)
    return directions[0], directions[1:]


def border_distances(
    radius: float, distance: float, samples: int = 720
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Angular distance and azimuth of the projected kernel's border about its centre.

    Parameters
    ----------
    radius
        Kernel radius r in units of the disc's radius, 0 < r.
    distance
        Distance d of the kernel's centre from the face's centre, same units, d ≥ 0.
    samples
        Border points, evenly spaced in paraboloid space.

    Returns
    -------
    alpha
        (samples,) float64, radians from the centre direction c to each border point.
    azimuth
        (samples,) float64, radians about c, 0 towards the rim (the face's +s).
    """
    centre, border = _centre_and_border(radius, distance, samples)
    alpha = np.arctan2(np.linalg.norm(np.cross(centre, border), axis=-1), border @ centre)
    # Tangent frame at c: e1 along increasing s (towards the rim), e2 along t.
    e1 = np.array([1.0 - distance * distance, 0.0, -2.0 * distance])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(centre, e1)
    tangent = border - (border @ centre)[:, None] * centre
    return alpha, np.arctan2(tangent @ e2, tangent @ e1)


def kernel_distortion(radius: float, distance: float, samples: int = 720) -> float:
    """Seed 004 Figure 3's error: the border distances' largest deviation from ρ, relative.

    Parameters
    ----------
    radius, distance, samples
        As in :func:`border_distances`.

    Returns
    -------
    float
        (max α − min α) / (max α + min α): the distances span ρ (1 ± e) with ρ the
        mid-range, which is the projected circle's angular radius.
    """
    alpha, _ = border_distances(radius, distance, samples)
    return float((alpha.max() - alpha.min()) / (alpha.max() + alpha.min()))


def analytic_distortion(radius: npt.ArrayLike, distance: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Closed form of :func:`kernel_distortion` (module docstring), broadcast.

    Parameters
    ----------
    radius, distance
        (...) float, r > 0 and d ≥ 0 in units of the disc's radius.

    Returns
    -------
    (...) float64
        e(r, d) = (2 atan d − atan(d + r) − atan(d − r)) / (atan(d + r) − atan(d − r)).
    """
    r = np.asarray(radius, dtype=np.float64)
    d = np.asarray(distance, dtype=np.float64)
    outer, inner = np.arctan(d + r), np.arctan(d - r)
    return (2.0 * np.arctan(d) - outer - inner) / (outer - inner)
