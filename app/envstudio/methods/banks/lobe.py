"""The Banks BRDF of seed 004 §5.3 and the ring form of its 3D environment map (no GL).

Seed 004 §5.3 extends Banks' model with a sharpness s ∈ [0, 1)::

    f(v, l) = (√(1 − ⟨l,t⟩²) √(1 − ⟨v,t⟩²) − ⟨l,t⟩⟨v,t⟩ − s) / (1 − s)²

and, dropping the self-shadowing term ⟨n,l⟩, gets the three-dimensional map::

    L_banks(t, ⟨v,t⟩) = ∫_S² f(v, l) L_i(l) dl                        (§5.3)

The bracket is negative away from the highlight; a BRDF cannot be, so
:func:`lobe` clamps it at zero (the paper leaves this implicit). With
a = ⟨l,t⟩ = cos θ and ⟨v,t⟩ = cos θ_v the bracket is cos(θ − ψ) − s with
ψ = π − θ_v: the lobe is the cone of directions at angle ψ from t (the mirror
cone about a fibre), of angular half-thickness acos(s).

Ring form. f depends on l only through ⟨l,t⟩, so the spherical integral splits
into the environment integrated around rings about t and a 1-D integral over θ::

    L_banks(t, cos θ_v) = ∫_0^π f(cos θ, cos θ_v) sin θ R_t(θ) dθ,
    R_t(θ) = ∫_0^2π L_i(cos θ t + sin θ (cos φ e₁ + sin φ e₂)) dφ

with (t, e₁, e₂) orthonormal. Sampling R_t at K bin centres θ_k = (k + ½)π/K and
taking it piecewise linear between them (constant past the first and last)
makes the map a weighted sum L_banks(t, cos θ_v) = Σ_k w_k(θ_v) R_t(θ_k), the
weights w_k = ∫ f sin θ hat_k(θ) dθ computed once per s (:func:`ring_weights`).
That is what both builders do (methods/banks/): K·M ring samples and K
multiply-adds per texel instead of one BRDF evaluation per environment texel.

The map is indexed by t on the front paraboloid face (core/paraboloid.py) and by
w = θ_v / π = acos⟨v,t⟩ / π. One hemisphere of t suffices: f is unchanged under
(t, ⟨v,t⟩) → (−t, −⟨v,t⟩) (both ⟨l,t⟩ and ⟨v,t⟩ change sign), so a lookup with
t_z < 0 reads (−t, −⟨v,t⟩) (:func:`fold`). The paraboloid is the cheapest map of
a hemisphere (one division, GLSL twin in shaders/common/paraboloid.glsl), its
solid angle varies only 4× across the disc (a sphere map's is singular at the
rim, a lat-long's at the poles), and its border texels hold directions just past
the rim, so filtering at the fold stays continuous. The third coordinate is the
angle θ_v rather than ⟨v,t⟩ itself so that slices are evenly spaced in the
angle the cone moves by (a uniform ⟨v,t⟩ would crowd them near θ_v = 90° and
leave 8° gaps near the poles with 64 slices).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.core import paraboloid

__all__ = [
    "BORDER",
    "bin_angles",
    "fold",
    "lobe",
    "lobe_integral",
    "orthonormal_basis",
    "ring_directions",
    "ring_weights",
    "slice_angles",
    "texel_tangents",
    "texture_coordinates",
]

#: Border of the tangent face in texels (directions past the rim, for filtering).
BORDER = 2
#: Sub-samples per bin of the weights' midpoint quadrature.
_WEIGHT_SUBSAMPLES = 64


def _check_sharpness(sharpness: float) -> float:
    s = float(sharpness)
    if not 0.0 <= s < 1.0:
        raise ValueError(f"sharpness={sharpness}: expected a number in [0, 1)")
    return s


def lobe(
    l_dot_t: npt.ArrayLike, v_dot_t: npt.ArrayLike, sharpness: float
) -> npt.NDArray[np.float64]:
    """The Banks BRDF of seed 004 §5.3, clamped at zero.

    Parameters
    ----------
    l_dot_t, v_dot_t
        (...) float, ⟨l,t⟩ and ⟨v,t⟩ in [−1, 1] (broadcast against each other).
    sharpness
        s ∈ [0, 1).

    Returns
    -------
    (...) float64
        max(0, √(1 − a²) √(1 − b²) − a b − s) / (1 − s)², 1/sr.
    """
    s = _check_sharpness(sharpness)
    a = np.clip(np.asarray(l_dot_t, np.float64), -1.0, 1.0)
    b = np.clip(np.asarray(v_dot_t, np.float64), -1.0, 1.0)
    bracket = np.sqrt(1.0 - a * a) * np.sqrt(1.0 - b * b) - a * b - s
    return np.maximum(bracket, 0.0) / (1.0 - s) ** 2


def lobe_integral(v_dot_t: npt.ArrayLike, sharpness: float) -> npt.NDArray[np.float64]:
    """∫_S² f(v, l) dl in closed form: the map of a unit environment.

    With a = cos θ and ψ = π − θ_v the integral is 2π ∫ (cos(θ − ψ) − s) sin θ dθ
    over θ ∈ [max(0, ψ − w), min(π, ψ + w)], w = acos s, whose antiderivative
    is −¼ cos(2θ − ψ) + ½ θ sin ψ + s cos θ.

    Parameters
    ----------
    v_dot_t
        (...) float, ⟨v,t⟩ in [−1, 1].
    sharpness
        s ∈ [0, 1).

    Returns
    -------
    (...) float64
        The integral, sr · (1/sr): dimensionless, > 0.
    """
    s = _check_sharpness(sharpness)
    b = np.clip(np.asarray(v_dot_t, np.float64), -1.0, 1.0)
    psi = np.pi - np.arccos(b)
    w = np.arccos(s)
    lo, hi = np.maximum(0.0, psi - w), np.minimum(np.pi, psi + w)

    def primitive(theta):
        return -0.25 * np.cos(2.0 * theta - psi) + 0.5 * theta * np.sin(psi) + s * np.cos(theta)

    return 2.0 * np.pi * (primitive(hi) - primitive(lo)) / (1.0 - s) ** 2


def slice_angles(slices: int) -> npt.NDArray[np.float64]:
    """(B,) float64, θ_v of the slice centres in radians: (j + ½) π / B."""
    return (np.arange(slices) + 0.5) * np.pi / slices


def bin_angles(bins: int) -> npt.NDArray[np.float64]:
    """(K,) float64, θ of the ring bins' centres in radians: (k + ½) π / K."""
    return (np.arange(bins) + 0.5) * np.pi / bins


def ring_weights(slices: int, bins: int, sharpness: float) -> npt.NDArray[np.float64]:
    """(B, K) float64 weights w_k(θ_v,j) of the ring form (module docstring).

    w_k = ∫_0^π f(cos θ, cos θ_v) sin θ hat_k(θ) dθ, where hat_k is the piecewise
    linear interpolant's basis function of node θ_k (constant continuation
    beyond the first and last node), by the midpoint rule with
    :data:`_WEIGHT_SUBSAMPLES` points per bin. 2π Σ_k w_k approximates
    :func:`lobe_integral` (within 1e-4 relative at s = 0.99, K = 128).
    """
    s = _check_sharpness(sharpness)
    fine = (np.arange(bins * _WEIGHT_SUBSAMPLES) + 0.5) * np.pi / (bins * _WEIGHT_SUBSAMPLES)
    position = np.clip(fine * bins / np.pi - 0.5, 0.0, bins - 1.0)  # in node units
    left = np.minimum(np.floor(position).astype(np.int64), bins - 2 if bins > 1 else 0)
    frac = position - left
    step = np.pi / (bins * _WEIGHT_SUBSAMPLES)
    weights = np.zeros((slices, bins))
    for j, theta_v in enumerate(slice_angles(slices)):
        f = lobe(np.cos(fine), np.cos(theta_v), s) * np.sin(fine) * step
        np.add.at(weights[j], left, f * (1.0 - frac))
        if bins > 1:
            np.add.at(weights[j], left + 1, f * frac)
    return weights


def orthonormal_basis(
    t: npt.NDArray[np.float64],
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(e₁, e₂), each (..., 3), completing unit vectors t to right-handed frames.

    Duff et al. 2017's branchless construction (no singularity), the same
    formula as shaders/banks/rings.glsl so both builders sample the same rings.
    """
    x, y, z = np.moveaxis(t, -1, 0)
    sign = np.where(z >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + z)
    b = x * y * a
    e1 = np.stack([1.0 + sign * x * x * a, sign * b, -sign * x], -1)
    e2 = np.stack([b, sign + y * y * a, -y], -1)
    return e1, e2


def ring_directions(
    t: npt.NDArray[np.float64], theta: float, samples: int
) -> npt.NDArray[np.float64]:
    """(..., M, 3) float64, M directions at angle θ from each unit t, φ = (m + ½) 2π / M."""
    e1, e2 = orthonormal_basis(t)
    phi = (np.arange(samples) + 0.5) * 2.0 * np.pi / samples
    c, s = np.cos(phi)[:, None], np.sin(phi)[:, None]
    ring = np.cos(theta) * t[..., None, :] + np.sin(theta) * (
        c * e1[..., None, :] + s * e2[..., None, :]
    )
    return ring


def texel_tangents(size: int) -> npt.NDArray[np.float64]:
    """(T, T, 3) float64 unit tangents of the map's texel centres (front face with border).

    Row i ↔ paraboloid t, column j ↔ s (core/paraboloid.py's layout); border
    texels hold directions just past the rim (z < 0).
    """
    centres = (np.arange(size) + 0.5) / size
    uv = np.stack(np.meshgrid(centres, centres, indexing="xy"), -1)
    return paraboloid.uv_to_direction(0, uv, size, BORDER)


def fold(
    tangents: npt.ArrayLike, v_dot_t: npt.ArrayLike
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(t, ⟨v,t⟩) moved onto the front hemisphere by the symmetry (−t, −⟨v,t⟩).

    Parameters
    ----------
    tangents
        (..., 3) float, unit tangents.
    v_dot_t
        (...) float.

    Returns
    -------
    tangents, v_dot_t
        (..., 3) and (...) float64 with t_z ≥ 0.
    """
    t = np.asarray(tangents, np.float64)
    b = np.asarray(v_dot_t, np.float64)
    flip = t[..., 2] < 0.0
    return np.where(flip[..., None], -t, t), np.where(flip, -b, b)


def texture_coordinates(
    tangents: npt.ArrayLike, v_dot_t: npt.ArrayLike, size: int
) -> npt.NDArray[np.float64]:
    """(..., 3) float64 3-D texture coordinates (u, v, w) of (t, ⟨v,t⟩) in a map of ``size``.

    The twin of shaders/banks/lookup.glsl: fold, front-paraboloid (u, v) with
    :data:`BORDER`, w = acos⟨v,t⟩ / π.
    """
    t, b = fold(tangents, v_dot_t)
    _, uv = paraboloid.direction_to_uv(t, size, BORDER)
    w = np.arccos(np.clip(b, -1.0, 1.0)) / np.pi
    return np.concatenate([uv, w[..., None]], -1)
