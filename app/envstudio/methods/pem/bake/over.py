"""The layered model refitted through its "over": alternating passes (issue 31; not in seed 003).

Seed 003 §4 ("Layered EMs") fits the two layers in sequence: the distant box map
to the segmented distant layer D, then the local ellipsoid's RGBA through the
composite (:func:`~envstudio.methods.pem.bake.infer.infer_local_over`)::

    I_layered = rgb_L + (1 − α_L)·I_D,    I_D = A_D x_D,  rgb_L = A_L x_rgb,  α_L = A_L x_α

At grazing views (along the floor, from above) many pixels whose reflected rays
differ reach the same ellipsoid texels, so the local layer cannot hold what its
α edges and self-reflections need, and the distant layer, fitted to D alone,
does not help: the layered playback falls behind the sphere at infinity
(studies/pem-orbit/README.md). With ``passes`` K ≥ 1 this module then minimises the
composite's own error by block coordinate descent, α held at its fit:

1. x_D ← argmin ||diag(1 − α_L) A_D x_D − (I − rgb_L)||² + R(x_D), where on the
   convex-hull pixels (which show I_D alone) the row is A_D x_D ≈ I;
2. x_rgb ← argmin ||A_L x_rgb − (I − (1 − α_L)·I_D)||² + R(x_rgb), I_D the new one,

K times (R the chain's smoothness and ties, :func:`~.infer.solve_mip`; ranges
RGB ≥ 0). Each step minimises the composite's objective (its squared error over the
fitted pixels plus R, and the coupling's term in a coupled bake) over one block, so
the objective cannot rise from step to step (up to the solves' tolerance and the
bounds); the error alone is not guaranteed to fall, but measured it did at every
pass (tests/test_pem_over.py). The distant layer then carries
what the local layer's texels cannot resolve, where α_L < 1; α stays the fit
of the traced segmentation, so the layers keep their meaning between views.
"""

from __future__ import annotations

import time

import numpy as np
import numpy.typing as npt
from scipy import sparse

from envstudio.methods.pem.bake.infer import MipInference, psnr, solve_mip

__all__ = ["refit_over"]


def _chain(flat: np.ndarray, like: list[np.ndarray]) -> list[np.ndarray]:
    """Split concatenated levels (Σ 6 n_k², C) into a chain shaped like ``like``."""
    out, start = [], 0
    for level in like:
        count = level.shape[0] * level.shape[1] * level.shape[2]
        out.append(flat[start : start + count].reshape(*level.shape[:3], flat.shape[1]))
        start += count
    return out


def refit_over(
    distant: MipInference,
    local: MipInference,
    incident: npt.ArrayLike,
    on_hull: npt.ArrayLike,
    size: int,
    passes: int,
    levels: int | None = None,
    smoothness: float = 1e-3,
    tie: float = 1e-3,
    anchors: dict[str, tuple[np.ndarray, float]] | None = None,
    **kw,
) -> tuple[MipInference, MipInference]:
    """Refit a part's distant and local colour through the layered composite (module docstring).

    Parameters
    ----------
    distant
        The distant chain of seed 003's fit (:func:`~.infer.infer_mip`, 3 channels).
    local
        The local chain fitted through the over (:func:`~.infer.infer_local_over`, 4
        channels, premultiplied RGB and α); its α is kept.
    incident
        (R², 3) or (R, R, 3) the traced incident layer I of the part.
    on_hull
        (R²,) or (R, R) bool: pixels whose centre ray hits a convex-hull triangle.
    size, levels, smoothness, tie
        n, L, λ and μ of the chains (:func:`~.infer.solve_mip`); other keywords (``rtol``)
        go to it too.
    passes
        K ≥ 1 alternations (step 1 then step 2).
    anchors
        Coupled inference (:mod:`~.infer`): ``{"distant": (mean, weight), "local": (mean,
        weight)}``, the neighbours' mean maps (Σ 6 n_k², 3 and 4) and γ|N(v)|; None:
        uncoupled.

    Returns
    -------
    distant, local : MipInference
        The refitted chains over the same matrices and pixels. ``distant.psnr`` is its
        lookup against the segmented layer it was first fitted to (it now also carries
        what the local layer cannot); ``local.psnr`` the composite's, as
        :func:`~.infer.infer_local_over`'s.
    """
    if int(passes) < 1:
        raise ValueError(f"over passes {passes}: expected at least 1")
    start = time.perf_counter()
    pixels = local.pixels
    A_d, A_l = distant.matrix[pixels], local.matrix[pixels]
    target = np.asarray(incident, np.float64).reshape(-1, 3)[pixels]
    hull = np.asarray(on_hull, bool).ravel()[pixels]
    x_d, x_l = distant.flat(), local.flat()
    alpha = (A_l @ x_l[:, 3:])[:, 0]
    show = np.where(hull, 1.0, 1.0 - alpha)  # how much of I_D each pixel shows
    A_shown = (sparse.diags(show) @ A_d).tocsr()
    keywords = {"levels": levels, "smoothness": smoothness, "tie": tie, **kw}
    coupled = {}
    for model in ("distant", "local"):
        mean, weight = (anchors or {}).get(model, (None, 0.0))
        coupled[model] = {} if not weight else {"anchor": mean, "coupling": weight}
    if coupled["local"]:
        coupled["local"]["anchor"] = np.asarray(coupled["local"]["anchor"]).reshape(-1, 4)[:, :3]
    rgb = x_l[:, :3]
    for _ in range(int(passes)):
        rest = np.where(hull[:, None], target, target - A_l @ rgb)
        chain, _ = solve_mip(A_shown, rest, size, **keywords, **coupled["distant"])
        x_d = np.concatenate([lv.reshape(-1, 3) for lv in chain])
        i_d = A_d @ x_d
        colour = np.where(hull[:, None], alpha[:, None] * i_d, target - show[:, None] * i_d)
        chain, _ = solve_mip(A_l, colour, size, **keywords, **coupled["local"])
        rgb = np.concatenate([lv.reshape(-1, 3) for lv in chain])
    x_l = np.concatenate([rgb, x_l[:, 3:]], axis=1)
    new_distant = MipInference(
        _chain(x_d, distant.levels), distant.matrix, pixels, distant.target,
        iterations=distant.iterations,
    )  # fmt: skip
    new_distant.psnr = psnr(A_d @ x_d, distant.target)
    new_local = MipInference(
        _chain(x_l, local.levels), local.matrix, pixels, local.target,
        iterations=local.iterations,
    )  # fmt: skip
    i_d = A_d @ x_d
    composite = np.where(hull[:, None], i_d, A_l @ rgb + (1.0 - alpha[:, None]) * i_d)
    new_local.psnr = psnr(composite, target)
    new_distant.seconds = distant.seconds
    new_local.seconds = local.seconds + time.perf_counter() - start
    return new_distant, new_local
