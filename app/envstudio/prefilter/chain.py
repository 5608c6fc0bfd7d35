"""A prefiltered cube mip chain for other engines: one Phong exponent per level.

Level k of an L-level chain is the cube of face n_k = n >> k prefiltered with
the normalised Phong lobe (prefilter.kernels.phong, seed 004 §4's L_phong) of

    N_k = 2^(scale · g_k + bias),   g_k = 1 − k / (L − 1)

the glossiness convention of cube-map filtering tools (cmft's
``--glossScale``/``--glossBias``, and the engines that read its output): an
engine picks the level from the material's glossiness and reads the map
along the reflection vector.

Each level is computed by the hierarchical prefilter (prefilter.hierarchical)
from the full-resolution source, whose pyramid is built once. Box-filtering
the source to a resolution that merely resolves each lobe (texels a quarter
of N^−½ wide, the CPU analogue of filtered importance sampling's coarser
source level) was tried and measured: on sunrise it moved the sun by up to
half a coarse texel and put levels 2–5 of a 128² chain off by 35–93 % of
their mean at the worst texel, against 0.01 % at full resolution.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from envstudio.prefilter import brute_force, hierarchical, kernels
from envstudio.prefilter.targets import target_directions

__all__ = ["ChainLevel", "gloss_exponents", "prefiltered_chain"]


@dataclass(frozen=True)
class ChainLevel:
    """One level of the chain.

    Attributes
    ----------
    faces
        (6, n_k, n_k, 3) float32 linear radiance, core.cubemap face order.
    exponent
        N_k, or the GGX α_k when ``kernel`` is "ggx" (prefilter.roughness).
    source_rows
        Rows of the lat-long source it was filtered from.
    kernel
        "phong" (prefilter.kernels.phong) or "ggx" (prefilter.kernels.ggx; α = 0: the
        environment itself).
    """

    faces: np.ndarray
    exponent: float
    source_rows: int
    kernel: str = "phong"


def gloss_exponents(levels: int, scale: float, bias: float) -> list[float]:
    """N_k = 2^(scale · (1 − k/(L − 1)) + bias) for k = 0 … L − 1 (module docstring)."""
    if levels == 1:
        return [2.0 ** (scale + bias)]
    return [2.0 ** (scale * (1.0 - k / (levels - 1)) + bias) for k in range(levels)]


def prefiltered_chain(
    radiance: npt.ArrayLike,
    size: int,
    levels: int,
    scale: float,
    bias: float,
    threshold: float = hierarchical.DEFAULT_THRESHOLD,
    *,
    threads: int | None = None,
    progress: bool = False,
) -> list[ChainLevel]:
    """Prefilter every level of the chain (module docstring).

    Parameters
    ----------
    radiance
        (h, 2h, 3) lat-long radiance.
    size
        Face edge n of level 0, a power of two.
    levels
        L, 1 ≤ L ≤ log2(n) + 1.
    scale, bias
        The glossiness mapping's constants.
    threshold
        The hierarchical method's T.
    threads, progress
        As prefilter.parallel.run_chunks.

    Returns
    -------
    list of ChainLevel
        Largest first.
    """
    pyramid = hierarchical.source_pyramid(radiance)
    rows = pyramid.shapes[0][0]
    chain = []
    for k, exponent in enumerate(gloss_exponents(levels, scale, bias)):
        faces = hierarchical.prefilter(
            pyramid,
            target_directions("cube", max(1, size >> k)),
            kernels.phong(exponent),
            threshold,
            threads=threads,
            progress=progress,
        )
        chain.append(ChainLevel(faces, exponent, rows))
    return chain


def chain_level_error(radiance: np.ndarray, level, samples: int = 256) -> tuple[float, float]:
    """RMS and max |level − brute force| over the level's mean, at sampled texels.

    The brute force (:func:`envstudio.prefilter.brute_force.prefilter`) sums the full-resolution
    source with the level's kernel (Phong N or GGX α > 0), at ``samples`` texels spread
    evenly over the faces (every k-th); both errors are relative to the brute-force mean there.

    Raises
    ------
    ValueError
        For a GGX level of α = 0: the environment resampled, not filtered (nothing to check).
    """
    n = level.faces.shape[1]
    directions = target_directions("cube", n).reshape(-1, 3)
    stride = max(1, len(directions) // samples)
    if level.kernel == "ggx" and level.exponent == 0.0:
        raise ValueError("a GGX level of alpha = 0 is the environment itself, not filtered")
    kernel = (kernels.ggx if level.kernel == "ggx" else kernels.phong)(level.exponent)
    truth = brute_force.prefilter(radiance, directions[::stride], kernel).astype(np.float64)
    got = level.faces.reshape(-1, 3)[::stride]
    mean = truth.mean()
    return float(np.sqrt(np.mean((got - truth) ** 2)) / mean), float(
        np.abs(got - truth).max() / mean
    )
