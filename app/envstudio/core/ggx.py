"""The GGX microfacet model the reference renders (``model=microfacet``), in NumPy.

The same functions as shaders/common/sampling.glsl and shaders/reference/material.glsl:

- D(h) = α² / (π ((n·h)² (α² − 1) + 1)²), the GGX (Trowbridge–Reitz) distribution;
- G2(l, v) = 2 (n·l)(n·v) / ((n·v) √((n·l)²(1 − α²) + α²) + (n·l) √((n·v)²(1 − α²) + α²)),
  the height-correlated Smith masking-shadowing (Heitz 2014);
- half vectors drawn in proportion to D(h) (n·h): tan² θ_h = α² u / (1 − u).

α is GGX's roughness itself, not the perceptual roughness √α. The reference takes a
Phong exponent N and renders α = √(2 / (4N + 2)) (a Phong exponent N is about a
Blinn exponent 4N, and Walter et al. 2007 match Blinn's exponent N_b to Beckmann's
α by α = √(2 / (N_b + 2))); :func:`alpha_for_exponent` and :func:`exponent_for_alpha`
are that mapping, used by the glossiness match of ``compare``.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

__all__ = [
    "alpha_for_exponent",
    "distribution",
    "exponent_for_alpha",
    "half_vector_cosine",
    "reflected_lobe_integral",
    "smith_g2",
]


def alpha_for_exponent(exponent: float) -> float:
    """GGX α of a Phong exponent N: √(2 / (4N + 2)) (material.glsl's microfacet_alpha)."""
    return math.sqrt(2.0 / (4.0 * float(exponent) + 2.0))


def exponent_for_alpha(alpha: float) -> float:
    """The Phong exponent N whose :func:`alpha_for_exponent` is α: (1/α² − 1) / 2."""
    return (1.0 / (float(alpha) ** 2) - 1.0) / 2.0


def distribution(n_dot_h: npt.ArrayLike, alpha: float) -> npt.NDArray[np.float64]:
    """GGX D(h) for cosines n·h (any shape), in 1/sr."""
    c = np.asarray(n_dot_h, dtype=np.float64)
    a2 = alpha * alpha
    d = c * c * (a2 - 1.0) + 1.0
    return a2 / (np.pi * d * d)


def smith_g2(
    n_dot_l: npt.ArrayLike, n_dot_v: npt.ArrayLike, alpha: float
) -> npt.NDArray[np.float64]:
    """Height-correlated Smith G2 for GGX (sampling.glsl's ggx_g2); 0 where n·l ≤ 0."""
    nl = np.maximum(np.asarray(n_dot_l, dtype=np.float64), 0.0)
    nv = np.asarray(n_dot_v, dtype=np.float64)
    a2 = alpha * alpha
    gl = nv * np.sqrt(nl * nl * (1.0 - a2) + a2)
    gv = nl * np.sqrt(nv * nv * (1.0 - a2) + a2)
    return 2.0 * nl * nv / np.maximum(gl + gv, 1e-300)


def half_vector_cosine(u: npt.ArrayLike, alpha: float) -> npt.NDArray[np.float64]:
    """cos θ_h of half vectors distributed as D(h)(n·h), at CDF values u ∈ [0, 1).

    cos² θ_h = (1 − u) / (1 + (α² − 1) u), i.e. tan² θ_h = α² u / (1 − u).
    """
    u = np.asarray(u, dtype=np.float64)
    return np.sqrt((1.0 - u) / (1.0 + (alpha * alpha - 1.0) * u))


def reflected_lobe_integral(alpha: float) -> float:
    """W(α) = ∫ D(h)/4 max(r·l, 0) dl with n = v = r: the split-sum lobe's normaliser.

    With μ = n·h = cos(θ/2) (θ the angle between r and l) and t = μ²,
    W = ∫_{½}^{1} α² (2t − 1) / (1 + a t)² dt, a = α² − 1, which is
    α²/a² [2 ln u + (2 + a)/u] from u = 1 + a/2 to u = α² (1/4 at α = 1).
    """
    a2 = float(alpha) ** 2
    a = a2 - 1.0
    if abs(a) < 1e-4:
        return 0.25 - a / 6.0  # first-order series about α = 1
    u0, u1 = 1.0 + 0.5 * a, a2

    def antiderivative(u: float) -> float:
        return 2.0 * math.log(u) + (2.0 + a) / u

    return a2 / (a * a) * (antiderivative(u1) - antiderivative(u0))
