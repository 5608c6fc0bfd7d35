"""A box-filtered cube mip chain and its trilinear lookup, in NumPy.

This is the CPU twin of the glossy environment map of seed 000 §4.2: the
environment as a cube map whose mip chain the hardware builds with a box filter
(``glGenerateMipmap``, each face filtered on its own, so level k of a face is
the mean of 2^k × 2^k texels of level 0 and the top level of a face is its
mean), looked up at mip level ℓ = b, the LOD bias of §5.2, with
``LINEAR_MIPMAP_LINEAR`` filtering::

    level 0   n × n       ─┐
    level 1   n/2 × n/2    │  bilinear sample at level ⌊ℓ⌋ and at ⌊ℓ⌋ + 1,
    …                      │  mixed linearly by ℓ − ⌊ℓ⌋ (trilinear);
    level L   1 × 1       ─┘  ℓ clamped to [0, L], L = log2 n

The bilinear samples are *seamless* across faces (core.resample.sample_cube):
that is what the GPU path samples, because moderngl enables
``GL_TEXTURE_CUBE_MAP_SEAMLESS`` for every context (envmap.conversions), and the
glossiness fit (prefilter.glossiness) must describe what is rendered. The
mip *generation* is still per face, so at high levels the six face means show
through as the coloured blocks of seed 000 Figure 4; seamless filtering only
blends them across the edges. (2003 hardware clamped the bilinear footprint
at each face edge instead, which changes only the lookups within half a texel
of that level from an edge.)

Face arrays follow core.cubemap: (6, n, n, c), OpenGL face order, rows ↔ t.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.core.resample import sample_cube

__all__ = ["box_mip_chain", "level_samples", "sample_mip_chain", "trilinear"]


def box_mip_chain(faces: npt.ArrayLike) -> list[npt.NDArray[np.float64]]:
    """Box-filtered mip chain of a cube map, each face filtered separately.

    Level k + 1 is the 2 × 2 mean of level k (``glGenerateMipmap``), hence the
    2^k × 2^k box mean of level 0.

    Parameters
    ----------
    faces
        (6, n, n, c) float, core.cubemap layout, n a power of two.

    Returns
    -------
    list of (6, n / 2^k, n / 2^k, c) float64
        Levels k = 0 … log2 n; the last is (6, 1, 1, c), each face's mean.
    """
    level = np.asarray(faces, dtype=np.float64)
    if level.ndim != 4 or level.shape[0] != 6 or level.shape[1] != level.shape[2]:
        raise ValueError(f"cube faces must have shape (6, n, n, c), got {level.shape}")
    n = level.shape[1]
    if n & (n - 1):
        raise ValueError(f"cube face size must be a power of two, got {n}")
    chain = [level]
    while level.shape[1] > 1:
        m = level.shape[1] // 2
        level = level.reshape(6, m, 2, m, 2, -1).mean(axis=(2, 4))
        chain.append(level)
    return chain


def level_samples(
    chain: list[npt.NDArray[np.float64]], directions: npt.ArrayLike
) -> npt.NDArray[np.float32]:
    """Seamless bilinear samples of every level of a mip chain.

    Parameters
    ----------
    chain
        Levels as :func:`box_mip_chain` returns them.
    directions
        (..., 3) float, world space, non-zero.

    Returns
    -------
    (L + 1, ..., c) float32
        Entry k is the bilinear lookup at level k (core.resample.sample_cube).
    """
    return np.stack([sample_cube(level, directions) for level in chain])


def trilinear(samples: npt.ArrayLike, level: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Mix per-level samples at a continuous mip level, as ``LINEAR_MIPMAP_LINEAR`` does.

    Parameters
    ----------
    samples
        (L + 1, ..., c) float, :func:`level_samples`.
    level
        ℓ, scalar or broadcastable to ``samples.shape[1:-1]``; clamped to [0, L].

    Returns
    -------
    (..., c) float64
        (1 − f)·samples[⌊ℓ⌋] + f·samples[⌊ℓ⌋ + 1] with f = ℓ − ⌊ℓ⌋.
    """
    samples = np.asarray(samples, dtype=np.float64)
    top = samples.shape[0] - 1
    lod = np.clip(np.asarray(level, dtype=np.float64), 0.0, top)
    lod = np.broadcast_to(lod, samples.shape[1:-1])
    lower = np.minimum(np.floor(lod).astype(np.int64), max(top - 1, 0))
    upper = np.minimum(lower + 1, top)
    f = (lod - lower)[..., None]
    pick = np.indices(lod.shape, sparse=True)
    return samples[(lower, *pick)] * (1.0 - f) + samples[(upper, *pick)] * f


def sample_mip_chain(
    chain: list[npt.NDArray[np.float64]], directions: npt.ArrayLike, level: npt.ArrayLike
) -> npt.NDArray[np.float64]:
    """Trilinear lookup of a box-filtered cube mip chain at mip level ℓ (seed 000 §5.2).

    Parameters
    ----------
    chain
        Levels as :func:`box_mip_chain` returns them.
    directions
        (..., 3) float, world space, non-zero.
    level
        ℓ = base LOD + bias b (the base LOD is 0 for a lookup with no screen-space
        derivatives), scalar or broadcastable to ``directions.shape[:-1]``;
        clamped to [0, log2 n].

    Returns
    -------
    (..., c) float64
        Filtered radiance.
    """
    return trilinear(level_samples(chain, directions), level)
