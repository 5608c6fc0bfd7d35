"""GGX roughness ↔ mip level of a split-sum chain: Filament's mapping, GL-free.

Shared by method ``splitsum`` (its GPU levels) and ``envstudio prefilter --chain --kernel
ggx`` (the chains written for other engines), so that both hold the same α per level.

Filament's cmgen ("map the lod to a linear_roughness, here we're using ^2"): of K levels,
level k holds the GGX α (the roughness itself, not the perceptual √α)

    α_k = (k / (K − 1))²,   so   lod = (K − 1) · √α,

linear in the perceptual roughness √α, which spreads the levels evenly over what the eye
sees as glossiness; level 0 (α = 0) is the environment itself (the mirror) and level K − 1
holds α = 1, the widest lobe. A chain of one level is the mirror alone.
"""

from __future__ import annotations

import math

__all__ = ["level_alphas", "level_of"]


def level_alphas(levels: int) -> list[float]:
    """α_k = (k/(K − 1))² for k = 0 … K − 1 (module docstring); [0] for K = 1.

    Raises
    ------
    ValueError
        Unless K ≥ 1.
    """
    if levels < 1:
        raise ValueError(f"levels must be >= 1, got {levels}")
    if levels == 1:
        return [0.0]
    return [(k / (levels - 1)) ** 2 for k in range(levels)]


def level_of(alpha: float, levels: int) -> tuple[int, float]:
    """(k, t): α lies between levels k and k + 1, t of the way (lod = (K − 1)·√α), K ≥ 2."""
    lod = (levels - 1) * math.sqrt(alpha)
    k = min(int(lod), levels - 2)
    return k, lod - k
