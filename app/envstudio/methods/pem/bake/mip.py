"""MIP chains of cube-map EMs for a PEM bake (seed 003 §4, "EM MIPMAPs").

A chain of a cube map with face edge n has L levels, level k of edge
n_k = n >> k, down to 1 (L = n.bit_length(): n = 64 gives 64, 32, …, 1, seven
levels). Inference solves all levels at once and the ``.pem`` file stores
levels k ≥ 1 "as residuals from corresponding decimated versions of the finest
level" (§4): :func:`decimate` is the 2 × 2 box filter of one face array, the
same on every face (faces are (6, n, n, ...), core/cubemap.py). A chain's
unknowns are concatenated level after level, texel f·n_k² + i·n_k + j of level
k at ``level_offsets(n, L)[k]`` plus that.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = ["decimate", "decimated_chain", "level_offsets", "mip_levels", "mip_sizes"]


def mip_levels(size: int) -> int:
    """L, the full chain's level count for face edge ``size`` (n >> (L − 1) ≥ 1)."""
    if size < 1:
        raise ValueError(f"cube face edge {size}: expected at least 1")
    return int(size).bit_length()


def mip_sizes(size: int, levels: int | None = None) -> list[int]:
    """Face edges n_k = n >> k of levels k = 0 … L − 1 (``levels`` default: the full chain)."""
    full = mip_levels(size)
    levels = full if levels is None else int(levels)
    if not 1 <= levels <= full:
        raise ValueError(f"{levels} MIP levels for a {size}² face: expected 1..{full}")
    return [size >> k for k in range(levels)]


def level_offsets(size: int, levels: int | None = None) -> npt.NDArray[np.int64]:
    """(L + 1,) int64: offset_k = Σ_{j<k} 6·n_j², the last entry the chain's texel count."""
    sizes = mip_sizes(size, levels)
    return np.concatenate([[0], np.cumsum([6 * n * n for n in sizes])]).astype(np.int64)


def decimate(faces: npt.ArrayLike) -> np.ndarray:
    """The 2 × 2 box filter of a cube map: (6, n, n, ...) → (6, n // 2, n // 2, ...).

    An odd edge drops its last row and column (chains here have power-of-two
    edges or stop at 1, where this is not called).
    """
    a = np.asarray(faces)
    n = a.shape[1] // 2
    if n < 1:
        raise ValueError(f"cannot decimate a {a.shape[1]}² face")
    a = a[:, : 2 * n, : 2 * n]
    return 0.25 * (a[:, 0::2, 0::2] + a[:, 1::2, 0::2] + a[:, 0::2, 1::2] + a[:, 1::2, 1::2])


def decimated_chain(finest: npt.ArrayLike, levels: int | None = None) -> list[np.ndarray]:
    """[finest, decimate(finest), decimate²(finest), …]: L levels of a (6, n, n, ...) map."""
    a = np.asarray(finest)
    chain = [a]
    for _ in mip_sizes(a.shape[1], levels)[1:]:
        chain.append(decimate(chain[-1]))
    return chain
