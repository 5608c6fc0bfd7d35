"""The split sum and the GGX integral it approximates, summed in NumPy over a lat-long map.

The check of ``splitsum`` against independent arithmetic (tests/test_splitsum_gl.py) and of
its small-α resolution (studies/splitsum-small-alpha/small_alpha.py): the reference's GGX
BRDF (F = 1)
times n·l over every texel with its exact solid angle, and Karis's split sum (SIGGRAPH 2013
course): the prefiltered lobe D(h)/4 ⟨r, l⟩ about r = reflect(−v, n), normalised, at the α_k
of the two chain levels α lies between, blended as the method does, times the directional
albedo A + B of the DFG table.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.core import ggx, latlong
from envstudio.methods.splitsum import dfg
from envstudio.methods.splitsum.method import level_of

__all__ = ["ggx_integral_and_split_sum"]


def ggx_integral_and_split_sum(
    radiance: npt.ArrayLike,
    n: npt.NDArray[np.float64],
    v: npt.NDArray[np.float64],
    alpha: float,
    levels: npt.ArrayLike,
) -> tuple[np.ndarray, np.ndarray]:
    """The GGX integral and the split sum at unit normals ``n`` seen from unit views ``v``.

    Parameters
    ----------
    radiance
        (H, 2H, 3) lat-long radiance.
    n, v
        (m, 3) unit normals and unit directions towards the viewer.
    alpha
        GGX α.
    levels
        The chain's α per level (a level of α = 0 is the mirror: the texel along r).

    Returns
    -------
    truth, split : (m, 3) float64
        ∫ f_GGX(l, v) (n·l) L(l) dl with F = 1, and the split sum's estimate of it.
    """
    radiance = np.asarray(radiance, dtype=np.float64)
    d = latlong.texel_directions(radiance.shape[0]).reshape(-1, 3)
    dw = latlong.texel_solid_angles(radiance.shape[0]).reshape(-1)
    L = radiance.reshape(-1, 3)
    n_dot_v = np.sum(n * v, -1, keepdims=True)
    n_dot_l, r_dot_l = n @ d.T, (2 * n_dot_v * n - v) @ d.T
    h = v[:, None, :] + d[None]
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    brdf_cos = ggx.distribution(np.einsum("pk,ptk->pt", n, h), alpha)
    brdf_cos *= ggx.smith_g2(np.maximum(n_dot_l, 0.0), n_dot_v, alpha) / (4 * n_dot_v)
    truth = np.where(n_dot_l > 0, brdf_cos, 0.0) * dw @ L
    k, t = level_of(alpha, len(levels))
    prefiltered = 0.0
    for level, weight in ((k, 1 - t), (k + 1, t)):
        if levels[level] == 0.0:
            prefiltered = prefiltered + weight * L[np.argmax(r_dot_l, axis=1)]
            continue
        lobe = ggx.distribution(np.sqrt((1 + r_dot_l) / 2), levels[level]) * r_dot_l
        lobe = np.where(r_dot_l > 0, lobe, 0.0)
        prefiltered = prefiltered + weight * (lobe * dw @ L) / (lobe @ dw)[:, None]
    albedo = dfg.dfg_entries(n_dot_v[:, 0], alpha, 4096).sum(1, keepdims=True)
    return truth, prefiltered * albedo
