"""One view's EM models and their predicted playback (seed 003 §4, Figures 1 and 6).

For one traced view (:class:`~envstudio.methods.pem.bake.trace.TracedView`) and its
per-pixel lookups (:class:`~envstudio.methods.pem.bake.lookups.PixelLookups`), every
reflector part p gets three inferred MIP chains, all levels in one solve
(:func:`~envstudio.methods.pem.bake.infer.infer_mip`), fitted on the part's *interior*
pixels: the pixel-centre ray is on p and every traced sample of the pixel is
(coverage_p = 1), so b and the playback's one lookup describe the same surface.

=========== === ==================================================== ============
model       C   b (the traced layer)                                 range
=========== === ==================================================== ============
``distant`` 3   D, the distant layer (box map)                       RGB ≥ 0
``local``   4   (α_L·L, α_L), premultiplied (ellipsoid map); α_L = 0 RGB ≥ 0,
                on convex-hull triangles (§4, :mod:`.hull`)          α ∈ [0, 1]
``sphere``  3   I = α_L·L + (1 − α_L)·D, the incident layer, with    RGB ≥ 0
                direction-only lookups (sphere at infinity, Fig. 6)
``ptm``     3   I, looked up by the surface point (x minus the EM     RGB ≥ 0
                origin): a per-view surface texture, seed 003 §6's
                PTM (Figure 7, issue 31)
=========== === ==================================================== ============

With ``over_passes`` K ≥ 1 (not in seed 003) the layered model's distant and
local colour are then refitted through their composite K times
(:mod:`~envstudio.methods.pem.bake.over`), which the paper's sequential fit (distant
to D, then the local RGBA through the over) leaves short at grazing views.

Coarser footprints (``coarser``, not in seed 003): seed 003 fits every level to
the lookups of the bake's own R × R image, whose footprints reach the coarse
levels only where the reflection is minified, so a playback at a smaller size
(which reads coarser levels everywhere) reads levels the solve barely
constrained (the speckle of Figure 5). With coarser footprints the same view,
box-filtered to R/2 (R/4, …), joins every solve with its own lookups at that
size: its rows ask the coarser levels for what a smaller image shows.

The static EM (Figure 1c, :func:`static_em`) is not inferred: it is a cube map
of the scene traced from the reflectors' centre with the reflectors hidden,
its levels the box-decimated chain, looked up like the sphere model.

The predicted playback (:func:`predict`) of a model M replaces the traced
incident layer by A x_M in the composition of seed 003 §4::

    C_pred = background + Σ_p coverage_p · ((1 − F)·d + F·I_M)
    I_layered = rgb_L + (1 − α_L)·I_D   (premultiplied "over"; I_D on hull triangles)
    I_sphere  = A_S x_S,   I_static = A_S x_static,   I_ptm = A_T x_T

and :func:`playback_psnr` compares it with the traced composite over the
interior pixels of all parts: the issue's "playback of the inferred maps
against the ray-traced composite, over the reflector's pixels".
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from scipy import sparse

from envstudio.core.cubemap import texel_directions
from envstudio.methods.pem.bake.infer import MipInference, infer_local_over, infer_mip, psnr
from envstudio.methods.pem.bake.lookups import CHANNELS, LOD_BIAS, MODELS, PLAYBACK, PixelLookups
from envstudio.methods.pem.bake.mip import decimated_chain, mip_sizes
from envstudio.methods.pem.bake.over import refit_over
from envstudio.methods.pem.bake.trace import TracedView

__all__ = [
    "PLAYBACK",
    "ViewModels",
    "fit_pixels",
    "hull_pixels",
    "infer_view_models",
    "playback_psnr",
    "predict",
    "static_em",
]


@dataclass
class ViewModels:
    """The inferred maps of one view.

    Attributes
    ----------
    fits : dict
        Model → P entries: a :class:`MipInference`, or None for a part with no
        interior pixel in the view.
    seconds : float
        Wall time of the solves.
    """

    fits: dict[str, list[MipInference | None]] = field(default_factory=dict)
    seconds: float = 0.0

    def maps(self, model: str, em_size: int, levels: int | None = None) -> list[np.ndarray]:
        """Levels of ``model``: list over k of (P, 6, n_k, n_k, C) float32, 0 for absent parts."""
        sizes = mip_sizes(em_size, levels)
        c = CHANNELS[model]
        out = [np.zeros((len(self.fits[model]), 6, n, n, c), np.float32) for n in sizes]
        for p, fit in enumerate(self.fits[model]):
            if fit is not None:
                for k, level in enumerate(fit.levels):
                    out[k][p] = level
        return out

    def psnr(self, model: str) -> np.ndarray:
        """(P,) float64 fit PSNR (A x against b), NaN for absent parts."""
        return np.array([np.nan if f is None else f.psnr for f in self.fits[model]])


def fit_pixels(view: TracedView, lookups: PixelLookups, part: int) -> npt.NDArray[np.bool_]:
    """(R, R) bool: the interior pixels of ``part`` (centre ray on it and coverage 1)."""
    return (lookups.part == part) & (view.coverage[part] >= 1.0)


def hull_pixels(lookups: PixelLookups, hull: list[npt.NDArray[np.bool_]]) -> np.ndarray:
    """(R, R) bool: pixels whose centre ray hits a convex-hull triangle of its part."""
    out = np.zeros(lookups.part.shape, bool)
    for p, mask in enumerate(hull):
        on = lookups.part == p
        out[on] = np.asarray(mask, bool)[lookups.triangle[on]]
    return out


def _targets(view: TracedView, part: int, on_hull: np.ndarray) -> dict[str, np.ndarray]:
    alpha = np.where(on_hull, 0.0, view.local_alpha[part]).astype(np.float64)[..., None]
    incident = view.incident()[part]
    return {
        # hull triangles show the distant map alone: fit it to what they show
        "distant": np.where(on_hull[..., None], incident, view.distant[part]),
        "local": np.concatenate([alpha * view.local_rgb[part], alpha], axis=-1),
        "sphere": incident,
    }


def infer_view_models(
    view: TracedView,
    lookups: PixelLookups,
    em_size: int,
    hull: list[npt.NDArray[np.bool_]],
    smoothness: float = 1e-3,
    tie: float = 1e-3,
    levels: int | None = None,
    lod_bias: float = LOD_BIAS,
    local_fit: str = "over",
    anchors: dict[str, list[np.ndarray | None]] | None = None,
    coupling: float = 0.0,
    models: tuple[str, ...] = MODELS,
    over_passes: int = 0,
    coarser: tuple[tuple[TracedView, PixelLookups], ...] = (),
    **kw,
) -> ViewModels:
    """Infer every model's MIP chain for every part of one view (module docstring).

    Parameters
    ----------
    view
        The traced view.
    lookups
        Its :func:`~envstudio.methods.pem.bake.lookups.pixel_lookups`.
    em_size
        n.
    hull
        P (T_p,) bool hull masks (:func:`~envstudio.methods.pem.bake.hull.reflector_hulls`).
    smoothness, tie, levels
        λ, μ and L of :func:`~envstudio.methods.pem.bake.infer.solve_mip`; other keywords go
        to it too.
    lod_bias
        Added to every lookup's level (``PixelLookups.matrix``); the playback must
        add the same.
    local_fit
        ``"over"``: the local chain fitted through the composite with the inferred
        distant layer (:func:`~envstudio.methods.pem.bake.infer.infer_local_over`; its fit
        PSNR is that of the layered I); ``"premultiplied"``: fitted alone to
        b = (α_L·L, α_L) (its PSNR that of b).
    anchors, coupling
        Coupled inference (issue 31, not in seed 003;
        :mod:`~envstudio.methods.pem.bake.infer`): per model, per part, None (that
        part is not coupled) or (mean, count), the (Σ 6 n_k², C) mean of ``count``
        neighbouring views' maps, drawn towards with weight γ·count, γ =
        ``coupling``. 0: independent.
    models
        The maps to infer: :data:`MODELS` (the three of seed 003 and the PTM's), or
        without ``ptm``.
    over_passes
        K ≥ 1: after seed 003's sequential fit, the distant and local colour are
        refitted through the layered composite K times
        (:func:`~envstudio.methods.pem.bake.over.refit_over`; not in seed 003; needs
        ``local_fit="over"``); 0: the paper's fit alone.
    coarser
        Coarser footprints of the same view (not in seed 003): pairs of the view
        halved (:meth:`~envstudio.methods.pem.bake.trace.TracedView.halved`, once per
        entry) and its lookups at that size, whose rows join every solve, so that the
        coarse levels a smaller playback reads are fitted too (module docstring). ():
        the view's own pixels alone, as seed 003.

    Returns
    -------
    ViewModels
    """
    if local_fit not in ("over", "premultiplied"):
        raise ValueError(f"local_fit {local_fit!r}: expected 'over' or 'premultiplied'")
    if over_passes and local_fit != "over":
        raise ValueError("over passes refit through the over: they need local_fit 'over'")
    start = time.perf_counter()
    footprints = [(view, lookups), *coarser]
    hulls = [hull_pixels(lk, hull) for _, lk in footprints]
    on_hull = np.concatenate([h.ravel() for h in hulls])
    out = ViewModels(fits={m: [] for m in models})

    def rows(model: str, p: int) -> sparse.csr_matrix:
        """The lookups of every footprint, stacked: (Σ R_i², Σ 6 n_k²)."""
        blocks = [lk.matrix(model, p, levels, em_size, lod_bias) for _, lk in footprints]
        return blocks[0] if len(blocks) == 1 else sparse.vstack(blocks, format="csr")

    def coupled(model: str, p: int) -> dict:
        """The coupling keywords of one solve ({} when uncoupled: today's solve)."""
        entry = None if anchors is None else anchors.get(model, [None] * (p + 1))[p]
        if not coupling or entry is None:
            return {}
        mean, count = entry
        return {"anchor": mean, "coupling": coupling * count}

    for p in range(len(view.part_names)):
        if not fit_pixels(view, lookups, p).any():
            for model in models:
                out.fits[model].append(None)
            continue
        pixels = np.concatenate([fit_pixels(v, lk, p).ravel() for v, lk in footprints])
        each = [_targets(v, p, h) for (v, _), h in zip(footprints, hulls, strict=True)]
        targets = {
            name: np.concatenate([t[name].reshape(-1, t[name].shape[-1]) for t in each])
            for name in each[0]
        }

        def solve(model, target, hi=np.inf, p=p, pixels=pixels):
            A = rows(model, p)
            return infer_mip(
                A, pixels, target, em_size, levels, smoothness, tie, 0.0, hi,
                **kw, **coupled(model, p),
            )  # fmt: skip

        distant = solve("distant", targets["distant"])
        if local_fit == "over":
            i_d = distant.render()
            incident = targets["sphere"].reshape(-1, 3).copy()
            hull_rows = on_hull.ravel()
            incident[hull_rows] = i_d[hull_rows]  # the playback shows I_D there
            local = infer_local_over(
                rows("local", p),
                pixels,
                incident,
                i_d,
                targets["local"][..., 3],
                em_size,
                levels,
                smoothness,
                tie,
                **kw,
                **coupled("local", p),
            )
            if over_passes:
                anchors_p = {m: tuple(coupled(m, p).values()) for m in ("distant", "local")}
                distant, local = refit_over(
                    distant, local, targets["sphere"], on_hull, em_size, over_passes,
                    levels, smoothness, tie, {m: a for m, a in anchors_p.items() if a}, **kw,
                )  # fmt: skip
        else:
            local = solve("local", targets["local"], [np.inf] * 3 + [1.0])
        out.fits["distant"].append(distant)
        out.fits["local"].append(local)
        out.fits["sphere"].append(solve("sphere", targets["sphere"]))
        if "ptm" in models:  # the surface texture shows the whole incident layer
            out.fits["ptm"].append(solve("ptm", targets["sphere"]))
    out.seconds = time.perf_counter() - start
    return out


def static_em(tracer, centre: npt.ArrayLike, size: int) -> npt.NDArray[np.float32]:
    """(6, n, n, 3) float32 the static EM (Figure 1c): the scene seen from ``centre``.

    One ray per texel centre from ``centre`` (e.g. ``Scene.reflector_centre()``)
    traced through the local objects only (reflectors hidden), shaded as the
    distant layer is (local objects diffuse, the environment where it misses).
    """
    d = texel_directions(size).reshape(-1, 3)
    o = np.broadcast_to(np.asarray(centre, dtype=np.float64), d.shape).copy()
    hit = tracer._intersect(True, o, d)
    return tracer._shade(*hit, o, d, 0).reshape(6, size, size, 3).astype(np.float32)


def predict(
    view: TracedView,
    lookups: PixelLookups,
    models: ViewModels,
    em_size: int,
    hull: list[npt.NDArray[np.bool_]],
    static: npt.ArrayLike | None = None,
    levels: int | None = None,
) -> dict[str, np.ndarray]:
    """The predicted playback composites (module docstring).

    Parameters
    ----------
    view, lookups, models, em_size, hull, levels
        As :func:`infer_view_models`; the lookups are the matrices ``models``
        carries (the static EM is looked up with the sphere model's).
    static
        (6, n, n, 3) static EM (:func:`static_em`); without it no ``"static"`` entry.

    Returns
    -------
    dict
        Name in :data:`PLAYBACK` → (R, R, 3) float64 C_pred.
    """
    npix = view.size * view.size
    on_hull = hull_pixels(lookups, hull).ravel()
    chain = None
    if static is not None:
        lv = decimated_chain(np.asarray(static, dtype=np.float64), len(mip_sizes(em_size, levels)))
        chain = np.concatenate([x.reshape(-1, 3) for x in lv])
    names = [
        n
        for n in PLAYBACK
        if (n != "static" or chain is not None) and (n != "ptm" or "ptm" in models.fits)
    ]
    out = {n: view.background.reshape(npix, 3).astype(np.float64) for n in names}
    for p in range(len(view.part_names)):
        fd = models.fits["distant"][p]
        if fd is None:
            continue
        fl, fs = models.fits["local"][p], models.fits["sphere"][p]
        i_d = fd.render()[:npix]  # the view's own rows (coarser footprints follow)
        loc = fl.render()[:npix]
        layered = loc[:, :3] + (1.0 - loc[:, 3:]) * i_d
        layered[on_hull] = i_d[on_hull]
        incident = {"layered": layered, "sphere": fs.render()[:npix]}
        if chain is not None:
            incident["static"] = fs.matrix[:npix] @ chain
        if "ptm" in models.fits:
            incident["ptm"] = models.fits["ptm"][p].render()[:npix]
        cov = view.coverage[p].reshape(npix, 1).astype(np.float64)
        f = view.fresnel[p].reshape(npix, 1).astype(np.float64)
        diffuse = (1.0 - f) * view.diffuse[p].reshape(npix, 3)
        for n in names:
            out[n] = out[n] + cov * (diffuse + f * incident[n])
    return {n: v.reshape(view.size, view.size, 3) for n, v in out.items()}


def playback_psnr(
    view: TracedView, lookups: PixelLookups, predicted: dict[str, np.ndarray]
) -> dict[str, float]:
    """PSNR (dB, peak = max of the composite there) of each prediction over interior pixels."""
    mask = np.zeros((view.size, view.size), bool)
    for p in range(len(view.part_names)):
        mask |= fit_pixels(view, lookups, p)
    if not mask.any():
        return {n: float("nan") for n in predicted}
    ref = view.composite[mask]
    return {n: psnr(v[mask], ref) for n, v in predicted.items()}
