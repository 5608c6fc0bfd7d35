"""Importance sampling of a lat-long environment by luminance (piecewise-constant 2D CDF).

The map is reduced to an importance image of at most ``max_height`` rows; texel
(i, j) gets weight w_ij = (lum_ij + ε·mean) · sin θ_i, so bright texels (suns)
are chosen in proportion to their contribution and every direction keeps a
nonzero density. A direction is drawn by picking a row from the marginal CDF,
a column from that row's conditional CDF, and a uniform point inside the
texel in (u, v). Its solid-angle density is

    pdf_ω(l) = p_uv(u, v) / (2π² sin θ),    p_uv = w_ij / Σw · (W·H),

since dω = 2π² sin θ du dv for the lat-long map (DESIGN.md convention).
shaders/reference/env_sampling.glsl draws from the same tables on the GPU.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from envstudio.core import latlong

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def luminance(rgb: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Rec. 709 luminance of (..., 3) linear RGB."""
    return np.asarray(rgb, dtype=np.float64) @ LUMINANCE


def box_downsample(image: npt.ArrayLike, factor: int) -> npt.NDArray[np.float64]:
    """Average ``factor`` × ``factor`` blocks of an (h, w, c) image (h, w divisible by factor)."""
    img = np.asarray(image, dtype=np.float64)
    h, w = img.shape[:2]
    return img.reshape(h // factor, factor, w // factor, factor, -1).mean(axis=(1, 3))


@dataclass
class EnvironmentDistribution:
    """Tables for drawing directions in proportion to environment luminance.

    Attributes
    ----------
    weights : (H, W) float64
        Unnormalised texel weights w_ij (luminance × sin θ, plus a floor).
    marginal_cdf : (H + 1,) float64
        CDF over rows, from 0 to 1.
    conditional_cdf : (H, W + 1) float64
        Per-row CDF over columns, each from 0 to 1.
    """

    weights: npt.NDArray[np.float64]
    marginal_cdf: npt.NDArray[np.float64]
    conditional_cdf: npt.NDArray[np.float64]

    @classmethod
    def from_latlong(
        cls, image: npt.ArrayLike, max_height: int = 256, floor: float = 1e-3
    ) -> EnvironmentDistribution:
        """Build the tables from an (h, 2h, 3) lat-long radiance map."""
        img = np.asarray(image, dtype=np.float64)
        factor = 1
        while img.shape[0] // factor > max_height and img.shape[0] % (2 * factor) == 0:
            factor *= 2
        small = box_downsample(img, factor) if factor > 1 else img
        lum = luminance(small)
        height = small.shape[0]
        sin_theta = np.sin(np.pi * (np.arange(height) + 0.5) / height)
        weights = (lum + floor * max(lum.mean(), 1e-12)) * sin_theta[:, None]
        row_sums = weights.sum(axis=1)
        conditional = np.concatenate(
            [np.zeros((height, 1)), np.cumsum(weights, axis=1) / row_sums[:, None]], axis=1
        )
        marginal = np.concatenate([[0.0], np.cumsum(row_sums) / row_sums.sum()])
        conditional[:, -1] = 1.0
        marginal[-1] = 1.0
        return cls(weights, marginal, conditional)

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) of the importance image."""
        return self.weights.shape

    def pdf(self, directions: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Solid-angle density pdf_ω of (..., 3) unit directions, in 1/sr."""
        uv = latlong.direction_to_uv(directions)
        h, w = self.shape
        i = np.clip((uv[..., 1] * h).astype(int), 0, h - 1)
        j = np.clip((uv[..., 0] * w).astype(int), 0, w - 1)
        p_uv = self.weights[i, j] / self.weights.sum() * (w * h)
        sin_theta = np.sqrt(np.maximum(1.0 - np.clip(directions[..., 1], -1, 1) ** 2, 1e-12))
        return p_uv / (2.0 * np.pi**2 * sin_theta)

    def sample(self, xi: npt.ArrayLike) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """Map (..., 2) uniform numbers in [0, 1) to directions and their pdf_ω."""
        xi = np.asarray(xi, dtype=np.float64)
        h, w = self.shape
        i = np.clip(np.searchsorted(self.marginal_cdf, xi[..., 1], side="right") - 1, 0, h - 1)
        lo, hi = self.marginal_cdf[i], self.marginal_cdf[i + 1]
        v = (i + (xi[..., 1] - lo) / np.maximum(hi - lo, 1e-300)) / h
        rows = self.conditional_cdf[i]
        j = np.clip((rows < xi[..., :1]).sum(axis=-1) - 1, 0, w - 1)
        lo = np.take_along_axis(rows, j[..., None], -1)[..., 0]
        hi = np.take_along_axis(rows, j[..., None] + 1, -1)[..., 0]
        u = (j + (xi[..., 0] - lo) / np.maximum(hi - lo, 1e-300)) / w
        directions = latlong.uv_to_direction(np.stack([u, v], axis=-1))
        return directions, self.pdf(directions)
