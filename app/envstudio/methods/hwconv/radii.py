"""Filter radii, sizes and shrink factors of seed 004 §5.2 (hardware prefiltering), no GL.

The Phong lobe ⟨r, l⟩^N is clamped to zero where it falls below ε, so it reaches
the angle θ_ε = acos(ε^(1/N)) from r (§5.2, "a limit when BRDF values from the
Phong model can be clamped to zero"). In a dual-paraboloid face (s, t) = (x, y) /
(1 + z) (core.paraboloid) whose unit disc has a radius of R texels, a circle of
angular radius θ_ε measures, in texels::

    r_s = R · tan(θ_ε / 2)                   centred on the paraboloid's centre (d = 0)
    r_l = R · (1 − tan((π/2 − θ_ε) / 2))     centred on the rim (d = 1), towards the centre

(the radial scale of the map, ds/dθ = (1 + s²)/2, doubles from centre to rim: "the
ratio between the smallest filter radius and largest filter radius is about 2").
The filter size is the kernel's width 2·⌈r⌉; with R = 256 (the paper's 512-texel
faces) this gives §5.2's table exactly: 174/260, 78/136, 56/100, 36/66, 26/48 for
N = 10, 50, 100, 250, 500 and ε = 0.1. While a size exceeds the maximum kernel
size the map and the filter are shrunk by 2 (steps 4–5; the paper's "while r_s <
hardware supported filter size" means "while larger"), which gives the table's
shrink factors 32/64, 16/32, 8/16, 8/16, 4/8 for a maximum of 7.

The two maps are blended per texel with the weight d² of map L (§5.2: "0 % of map
L … at the center … 25 % of map L … for d = 0.5"), d the distance from the face's
centre in units of the disc's radius.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from envstudio.plugin import ParameterError

__all__ = [
    "MAX_KERNEL",
    "FilterPlan",
    "blend_weight",
    "clamp_angle",
    "filter_size",
    "kernel_weights",
    "large_radius",
    "outward_radius",
    "plan_filters",
    "shrink_factor",
    "small_radius",
]

#: Largest kernel size (taps per row) the convolution shader holds.
MAX_KERNEL = 15


def clamp_angle(exponent: float, epsilon: float) -> float:
    """θ_ε = acos(ε^(1/N)) in radians: where the Phong lobe cos^N θ falls to ε (§5.2)."""
    _check_exponent(exponent)
    _check_epsilon(epsilon)
    return math.acos(epsilon ** (1.0 / exponent))


def small_radius(theta: float, disc_radius: float) -> float:
    """r_s in texels: a cap of angular radius ``theta`` (rad) at the paraboloid's centre.

    (s, t) = tan(θ/2) along any radius of the face (core.paraboloid), R texels per unit.
    """
    return disc_radius * math.tan(0.5 * theta)


def large_radius(theta: float, disc_radius: float) -> float:
    """r_l in texels: the same cap centred on the rim, its extent towards the centre.

    The rim is θ = π/2 from the face's axis; the cap's near edge lies at π/2 − θ,
    at s = tan((π/2 − θ)/2), so it spans R · (1 − tan((π/2 − θ)/2)) texels.
    """
    return disc_radius * (1.0 - math.tan(0.5 * (0.5 * math.pi - theta)))


def outward_radius(theta: float, disc_radius: float) -> float:
    """Texels the cap centred on the rim reaches beyond it: R · (tan((π/2 + θ)/2) − 1).

    The paraboloid stretches beyond the rim (ds/dθ = (1 + s²)/2 grows), so this is
    more than r_l (twice as much for N = 10, ε = 0.1); the exact kernel reads that far.
    """
    return disc_radius * (math.tan(0.5 * (0.5 * math.pi + theta)) - 1.0)


def filter_size(radius: float) -> int:
    """Kernel width 2·⌈r⌉ in texels of a kernel of radius ``radius`` texels (§5.2's table)."""
    return 2 * math.ceil(radius - 1e-9)


def shrink_factor(size: int, max_kernel: int) -> int:
    """Smallest power of two s with size / s ≤ max_kernel (§5.2, steps 4–5)."""
    if max_kernel < 1:
        raise ParameterError(f"max_kernel={max_kernel}: expected an integer >= 1")
    shrink = 1
    while size / shrink > max_kernel:
        shrink *= 2
    return shrink


def blend_weight(d: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Weight of map L at distance d from the face's centre: d², at most 1 (§5.2).

    Parameters
    ----------
    d
        (...) float, distance from the paraboloid's centre in units of the disc's
        radius (1 at the rim, more in the border).

    Returns
    -------
    (...) float64
        min(d², 1); the blended map is (1 − w) · S + w · L.
    """
    d = np.asarray(d, dtype=np.float64)
    return np.minimum(d * d, 1.0)


@dataclass(frozen=True)
class FilterPlan:
    """The two kernels of §5.2 for one exponent, clamp and map.

    Attributes
    ----------
    exponent, epsilon : float
        Phong exponent N and clamp ε.
    size, border : int
        Texels across the unit disc of one face (2R) and of border on each side.
    max_kernel : int
        Largest filter size in (shrunk) texels.
    theta : float
        θ_ε in radians.
    radius_small, radius_large : float
        r_s and r_l in texels of the full-size map.
    size_small, size_large : int
        Filter sizes 2·⌈r⌉ in texels of the full-size map.
    shrink_small, shrink_large : int
        Powers of two by which map and filter are shrunk (mip level log2 s).
    """

    exponent: float
    epsilon: float
    size: int
    border: int
    max_kernel: int
    theta: float
    radius_small: float
    radius_large: float
    size_small: int
    size_large: int
    shrink_small: int
    shrink_large: int

    @property
    def face_size(self) -> int:
        """Texels across a face, border included: size + 2 · border."""
        return self.size + 2 * self.border

    @property
    def disc_radius(self) -> float:
        """R, the unit disc's radius in texels."""
        return 0.5 * self.size

    def level(self, which: str) -> int:
        """Mip level log2 s of kernel ``which`` ("small" or "large")."""
        return int(math.log2(self.shrink_small if which == "small" else self.shrink_large))

    def required_border(self, one_pass: bool = False, exact: bool = False) -> float:
        """Texels of border the largest kernel in use reaches beyond the rim.

        r_s in one pass, r_l with both maps, the outward reach of the exact kernel
        (:func:`outward_radius`) with ``exact``.
        """
        if exact:
            return outward_radius(self.theta, self.disc_radius)
        return self.radius_small if one_pass else self.radius_large

    def check_border(self, one_pass: bool = False, exact: bool = False) -> None:
        """Raise ParameterError when the border is narrower than the kernel's reach.

        A kernel centred on the rim reads that many texels beyond it; shrinking scales
        the border and the kernel alike, so the condition is on full-size texels.
        """
        need = math.ceil(self.required_border(one_pass, exact) - 1e-9)
        if self.border < need:
            kernel = (
                "exact kernel's reach beyond the rim"
                if exact
                else "small kernel's r_s"
                if one_pass
                else "large kernel's r_l"
            )
            raise ParameterError(
                f"border={self.border}: expected an integer >= {need} (texels: the {kernel} "
                f"at phong_exponent={self.exponent:g}, epsilon={self.epsilon:g}, "
                f"size={self.size})"
            )


def plan_filters(
    exponent: float, epsilon: float, size: int, border: int, max_kernel: int = 7
) -> FilterPlan:
    """Radii, filter sizes and shrink factors of §5.2 for one exponent and map.

    Parameters
    ----------
    exponent
        Phong exponent N > 0.
    epsilon
        Clamp ε in (0, 1).
    size
        Texels across one face's unit disc (the paper: 512).
    border
        Texels of border on each side of the disc (the paper: 64); not checked here
        (:meth:`FilterPlan.check_border`).
    max_kernel
        Largest filter size in texels (the paper: 7, on an SGI O2).

    Returns
    -------
    FilterPlan
    """
    if not 1 <= max_kernel <= MAX_KERNEL:
        raise ParameterError(f"max_kernel={max_kernel}: expected an integer in [1, {MAX_KERNEL}]")
    theta = clamp_angle(exponent, epsilon)
    disc_radius = 0.5 * size
    r_s, r_l = small_radius(theta, disc_radius), large_radius(theta, disc_radius)
    size_s, size_l = filter_size(r_s), filter_size(r_l)
    return FilterPlan(
        exponent=float(exponent),
        epsilon=float(epsilon),
        size=int(size),
        border=int(border),
        max_kernel=int(max_kernel),
        theta=theta,
        radius_small=r_s,
        radius_large=r_l,
        size_small=size_s,
        size_large=size_l,
        shrink_small=shrink_factor(size_s, max_kernel),
        shrink_large=shrink_factor(size_l, max_kernel),
    )


def kernel_weights(plan: FilterPlan, which: str) -> npt.NDArray[np.float32]:
    """The Phong lobe sampled into the shrunk filter (§5.2, step 7), normalised to sum 1.

    Tap (i, j) of the (2K + 1)², K = ⌊max_kernel / 2⌋, grid lies ρ = s · |(i, j)|
    texels of the full-size map from the centre; its angle from the lobe's axis is
    the paraboloid's at the kernel's reference point: θ = 2 atan(ρ / R) at the centre
    (``small``), θ = π/2 − 2 atan(1 − ρ / R) inwards from the rim (``large``). The
    weight is cos^N θ, zero where that is below ε (so zero beyond r_s or r_l).

    Parameters
    ----------
    plan
        The filters.
    which
        ``small`` (map S) or ``large`` (map L).

    Returns
    -------
    (2K + 1, 2K + 1) float32
        Weights indexed [j + K, i + K] (row = t offset), summing to 1.
    """
    if which not in ("small", "large"):
        raise ValueError(f"which must be 'small' or 'large', got {which!r}")
    k = plan.max_kernel // 2
    shrink = plan.shrink_small if which == "small" else plan.shrink_large
    offsets = np.arange(-k, k + 1, dtype=np.float64)
    rho = shrink * np.hypot(*np.meshgrid(offsets, offsets)) / plan.disc_radius
    if which == "small":
        theta = 2.0 * np.arctan(rho)
    else:
        theta = 0.5 * np.pi - 2.0 * np.arctan(1.0 - np.minimum(rho, 1.0))
    lobe = np.cos(np.minimum(theta, 0.5 * np.pi)) ** plan.exponent
    weights = np.where(lobe >= plan.epsilon, lobe, 0.0)
    weights[k, k] = 1.0  # the centre tap always counts
    return (weights / weights.sum()).astype(np.float32)


def _check_exponent(exponent: float) -> None:
    if not exponent > 0 or not math.isfinite(exponent):
        raise ParameterError(f"phong_exponent={exponent}: expected a number > 0")


def _check_epsilon(epsilon: float) -> None:
    if not 0 < epsilon < 1:
        raise ParameterError(f"epsilon={epsilon}: expected a number in (0, 1)")
