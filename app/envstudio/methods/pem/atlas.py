"""PEM maps packed for the playback shader (shaders/pem/atlas.glsl).

Every view's and part's maps of one EM model, all MIP levels, go into one
RGBA32F 2D texture in a flat texel order that is the column order of the bake's
rendering matrix (methods/pem/bake/infer.py ``trilinear_matrix``): map m = v·P + p
starts at m·T, T = Σ_k 6 n_k² (n_k = n >> k), level k at Σ_{j<k} 6 n_j², texel
(face f, row i, column j) of level k at offset_k + f n_k² + i n_k + j. Flat index
x lies at column x mod W, row x div W. All views stay resident (seed 003 §6
switched textures per view; here a view switch costs no upload).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

__all__ = ["ATLAS_WIDTH", "atlas_shape", "flat_maps", "pack_atlas", "pack_flags"]

#: Texels per atlas row (every GL 3.3 implementation allows 4096).
ATLAS_WIDTH = 4096


def flat_maps(levels: Sequence[npt.ArrayLike]) -> npt.NDArray[np.float32]:
    """All levels of every map in flat texel order.

    Parameters
    ----------
    levels
        L arrays (V, P, 6, n_k, n_k, C), level k's face edge n_k = n >> k.

    Returns
    -------
    (V·P·T, 4) float32
        The texels, C channels padded with zeros to 4.
    """
    first = np.asarray(levels[0])
    maps, channels = first.shape[0] * first.shape[1], first.shape[-1]
    flat = np.concatenate(
        [np.asarray(a, dtype=np.float32).reshape(maps, -1, channels) for a in levels], axis=1
    ).reshape(-1, channels)
    out = np.zeros((flat.shape[0], 4), np.float32)
    out[:, :channels] = flat
    return out


def atlas_shape(texels: int, width: int = ATLAS_WIDTH) -> tuple[int, int]:
    """(rows, columns) of an atlas holding ``texels`` texels ``width`` to a row."""
    return max(1, -(-int(texels) // width)), width


def pack_atlas(levels: Sequence[npt.ArrayLike], width: int = ATLAS_WIDTH) -> np.ndarray:
    """The atlas image of one model's maps.

    Parameters
    ----------
    levels
        L arrays (V, P, 6, n_k, n_k, C).
    width
        Texels per row, W.

    Returns
    -------
    (H, W, 4) float32
        Row 0 first (texture row 0), zero past the last texel.
    """
    flat = flat_maps(levels)
    rows, cols = atlas_shape(len(flat), width)
    out = np.zeros((rows * cols, 4), np.float32)
    out[: len(flat)] = flat
    return out.reshape(rows, cols, 4)


def pack_flags(flags: Sequence[npt.ArrayLike], width: int = ATLAS_WIDTH) -> tuple:
    """Per-triangle flags of every part in one (H, W) uint8 image.

    Parameters
    ----------
    flags
        P arrays (T_p,) bool, one flag per triangle of each part in draw order.
    width
        Flags per row.

    Returns
    -------
    image : (H, W) uint8
        The flags of part 0, then part 1, ... in flat order.
    offsets : list of int
        First flat index of each part.
    """
    arrays = [np.asarray(f, dtype=np.uint8).reshape(-1) for f in flags]
    offsets = [int(o) for o in np.cumsum([0] + [len(a) for a in arrays])[:-1]]
    flat = np.concatenate(arrays) if arrays else np.zeros(0, np.uint8)
    rows, cols = atlas_shape(len(flat), width)
    out = np.zeros(rows * cols, np.uint8)
    out[: len(flat)] = flat
    return out.reshape(rows, cols), offsets
