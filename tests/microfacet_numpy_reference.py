"""The reference's untraced GGX term summed in NumPy, independently of exact_lobes.py.

The check of the microfacet exact reference (tests/test_exact_microfacet.py) and of its
checked error (studies/exact-reference/microfacet_speed.py), written from the formulas of
shaders/common/sampling.glsl and shaders/reference/material.glsl alone:

    ∫ L(l) D(h) G2(l, v) F(v·h) / (4 ⟨n, v⟩) dl over ⟨n, l⟩ > 0,

D the GGX distribution, G2 the height-correlated Smith masking-shadowing (with
``smith="separable"`` Mitsuba 3's uncorrelated G1(v) G1(l) instead, the like-with-like check
of studies/exact-reference/mitsuba_ggx.py), F Schlick's per channel at ⟨v, h⟩,
h = (l + v)/|l + v|, the map a function constant over each lat-long texel. :func:`ggx_sum`
integrates it texel by texel, each texel cut into s × s parts of 3 × 3 Gauss–Legendre
points in (θ, φ), s chosen per sample and texel from the lobe's own scale where the texel
lies (in half-vector space, where the lobe is round: its width α at the peak, its distance
from n in the tails; a texel's extent there is its own over 2 ⟨v, h⟩, which grows as the
view grazes); :func:`ggx_albedo` integrates the lobe under a constant map in half-vector
space, (θ_h, φ_h) about n, with dl = 4 ⟨v, h⟩ dh.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from envstudio.core.latlong import direction_to_uv, texel_directions, uv_to_direction

_X, _W = np.polynomial.legendre.leggauss(3)


#: The Smith masking-shadowing terms :func:`ggx_lobe` knows: ours (shaders/common/sampling.glsl)
#: and Mitsuba 3's (``MicrofacetDistribution::G`` of render/microfacet.h).
SMITH_TERMS = ("correlated", "separable")


def ggx_lobe(n, v, light, alpha: float, fresnel, smith: str = "correlated") -> np.ndarray:
    """D G F(v·h) / (4 ⟨n, v⟩), zero where ⟨n, l⟩ ≤ 0; (..., 3 channels) for n, v and the
    light directions l (..., 3) that broadcast together.

    G is the height-correlated Smith G2 (``smith="correlated"``, the reference's) or the
    separable G1(v) G1(l), G1(x) = 2 ⟨n, x⟩ / (⟨n, x⟩ + √(α² + (1 − α²) ⟨n, x⟩²))
    (``"separable"``, Mitsuba 3's ``roughconductor``).
    """
    n_dot_l = np.sum(n * light, axis=-1)
    n_dot_v = np.sum(n * v, axis=-1)
    h = light + v
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    n_dot_h = np.sum(n * h, axis=-1)
    v_dot_h = np.sum(v * h, axis=-1)
    a2 = alpha * alpha
    d = a2 / (math.pi * (n_dot_h * n_dot_h * (a2 - 1.0) + 1.0) ** 2)
    nl = np.maximum(n_dot_l, 0.0)
    root_l = np.sqrt(nl * nl * (1.0 - a2) + a2)
    root_v = np.sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2)
    if smith == "correlated":
        g = 2.0 * nl * n_dot_v / np.maximum(n_dot_v * root_l + nl * root_v, 1e-300)
    elif smith == "separable":
        g = 4.0 * nl * n_dot_v / np.maximum((nl + root_l) * (n_dot_v + root_v), 1e-300)
    else:
        raise ValueError(f"smith={smith!r}: expected one of {SMITH_TERMS}")
    f0 = np.asarray(fresnel, dtype=np.float64)
    f = f0 + (1.0 - f0) * ((1.0 - np.clip(v_dot_h, 0.0, 1.0)) ** 5)[..., None]
    return np.where(n_dot_l > 0.0, d * g / (4.0 * n_dot_v), 0.0)[..., None] * f


def ggx_sum(
    radiance: npt.ArrayLike,
    normals: npt.ArrayLike,
    views: npt.ArrayLike,
    alpha: float,
    fresnel,
    ratio: float = 0.5,
    max_split: int = 64,
    horizon_split: int = 4,
    bright_split: int = 64,
    budget: int = 1 << 21,
    smith: str = "correlated",
) -> npt.NDArray[np.float64]:
    """The GGX term of each (n, v) under the lat-long ``radiance`` (h, w, 3); (s, 3).

    A texel is cut into s × s parts, s the least power of two (at most ``max_split``) that
    makes a part's extent in half-vector space under ``ratio`` × max(α, the texel's
    distance from n there); each part takes 3 × 3 Gauss points. ``smith`` picks the
    masking-shadowing term (:func:`ggx_lobe`).
    """
    image = np.asarray(radiance, dtype=np.float64)
    normals = np.asarray(normals, dtype=np.float64)
    views = np.asarray(views, dtype=np.float64)
    h, w = image.shape[:2]
    rows, cols = np.divmod(np.arange(h * w), w)
    centres = texel_directions(h, w).reshape(-1, 3)
    widest = np.maximum(np.sin(rows * math.pi / h), np.sin((rows + 1) * math.pi / h))
    half_diagonal = 0.5 * np.hypot(math.pi / h, 2.0 * math.pi / w * widest)
    texel_radiance = image.reshape(-1, 3)
    brightness = texel_radiance.max(axis=1)
    bright = brightness > 20.0 * brightness.mean()
    out = np.zeros((len(normals), 3))
    per_chunk = max(1, (1 << 21) // (h * w))
    for first in range(0, len(normals), per_chunk):
        n = normals[first : first + per_chunk]
        v = views[first : first + per_chunk]
        half = centres[None] + v[:, None]
        half /= np.maximum(np.linalg.norm(half, axis=-1, keepdims=True), 1e-12)
        from_n = np.arccos(np.clip(np.einsum("stk,sk->st", half, n), -1.0, 1.0))
        extent = half_diagonal / (2.0 * np.maximum(np.einsum("stk,sk->st", half, v), 0.05))
        scale = ratio * np.maximum(alpha, from_n - extent)
        split = 2 ** np.ceil(np.log2(np.maximum(extent / scale, 1.0)))
        # the horizon, where the lobe (G2 ∝ ⟨n, l⟩) has a kink: finer parts over the texels
        # it crosses
        horizon = np.abs(np.arcsin(np.clip(np.einsum("tk,sk->st", centres, n), -1.0, 1.0)))
        across = np.where(bright, bright_split, horizon_split)
        split = np.where(horizon < half_diagonal, np.maximum(split, across), split)
        split = np.minimum(split, max_split).astype(int)
        for s in np.unique(split):
            sample, texel = np.nonzero(split == s)
            t = ((np.arange(s)[:, None] + 0.5 * (1.0 + _X)) / s).ravel()
            weight = np.tile(0.5 * _W / s, s)
            step = max(1, budget // (9 * s * s))
            for k in range(0, len(sample), step):
                si, ti = sample[k : k + step], texel[k : k + step]
                theta = (rows[ti][:, None] + t) * (math.pi / h)
                u = (cols[ti][:, None] + t) / w
                uv = np.stack(np.broadcast_arrays(u[:, None, :], theta[:, :, None] / math.pi), -1)
                light = uv_to_direction(uv)
                d_omega = (math.pi / h * weight * np.sin(theta))[:, :, None] * (
                    2.0 * math.pi / w * weight
                )
                lobe = ggx_lobe(
                    n[si][:, None, None], v[si][:, None, None], light, alpha, fresnel, smith
                )
                part = np.einsum("pabc,pab->pc", lobe, d_omega) * texel_radiance[ti]
                np.add.at(out, first + si, part)
    return out


def ggx_albedo(
    normals: npt.ArrayLike,
    views: npt.ArrayLike,
    alpha: float,
    fresnel,
    theta_points: int = 8,
    phi_points: int = 256,
    radiance: npt.ArrayLike | None = None,
) -> npt.NDArray[np.float64]:
    """∫ D G2 F(v·h) / (4 ⟨n, v⟩) dl for each (n, v) (the GGX term under L = 1), (s, 3):
    over half vectors, θ_h in panels graded from α/8 near n to 0.1 rad, ``theta_points``
    Gauss points each, φ_h at ``phi_points`` midpoints. With ``radiance`` (an (h, w, 3)
    lat-long map), ∫ L(l) ... dl instead, L read at the texel each point's l falls in (for
    maps smooth at the scale of the points: the sum does not follow texel edges)."""
    edges, step = [0.0], alpha / 8.0
    while edges[-1] + step < 0.5 * math.pi:
        edges.append(edges[-1] + step)
        if edges[-1] >= 0.5 * alpha:
            step = min(1.5 * step, 0.1)
    edges = np.array([*edges, 0.5 * math.pi])
    x, wg = np.polynomial.legendre.leggauss(theta_points)
    middle, half = 0.5 * (edges[1:] + edges[:-1]), 0.5 * np.diff(edges)
    theta = (middle[:, None] + half[:, None] * x).ravel()
    theta_weight = (half[:, None] * wg).ravel() * np.sin(theta)
    phi = (np.arange(phi_points) + 0.5) * 2.0 * math.pi / phi_points
    out = np.zeros((len(normals), 3))
    pairs = zip(np.asarray(normals, float), np.asarray(views, float), strict=True)
    for k, (n, v) in enumerate(pairs):
        t1 = v - (n @ v) * n
        if np.linalg.norm(t1) < 1e-6:
            t1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(n, t1)
        sin_t, cos_t = np.sin(theta)[:, None, None], np.cos(theta)[:, None, None]
        h = sin_t * (np.cos(phi)[:, None] * t1 + np.sin(phi)[:, None] * t2) + cos_t * n
        v_dot_h = h @ v
        light = 2.0 * v_dot_h[..., None] * h - v
        jacobian = np.where(v_dot_h > 0.0, 4.0 * v_dot_h, 0.0)  # dl = 4 <v, h> dh
        lobe = ggx_lobe(n, v, light, alpha, fresnel) * jacobian[..., None]
        if radiance is not None:
            lobe *= _texel_radiance(np.asarray(radiance, dtype=np.float64), light)
        out[k] = np.einsum("tpc,t->c", lobe, theta_weight) * (2.0 * math.pi / phi_points)
    return out


def _texel_radiance(radiance: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """The map's texel at each of the (..., 3) unit directions, (..., 3)."""
    rows, columns = radiance.shape[:2]
    uv = direction_to_uv(directions.reshape(-1, 3))
    column = np.minimum((uv[:, 0] * columns).astype(int), columns - 1) % columns
    row = np.clip((uv[:, 1] * rows).astype(int), 0, rows - 1)
    return radiance[row, column].reshape(*directions.shape[:-1], 3)
