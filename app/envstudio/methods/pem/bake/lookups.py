"""Per-pixel EM lookups and the trilinear rendering matrix of a PEM bake (seed 003 §4).

Seed 003 §4 ("EM Inference") infers an EM through the rendering matrix A of the
playback renderer; "Inference and playback then agree by construction" when A
is built from the texture coordinates and MIP level the playback shader uses
(issue 18). This module fixes that lookup as a contract shared by the CPU
bake (:func:`pixel_lookups`) and the playback's GL pass, which returns the
same :class:`PixelLookups`.

Per pixel (the playback draws one sample per pixel)
----------------------------------------------------
1. One camera ray through the pixel centre (column + ½, row + ½; the camera of
   :meth:`SceneTracer.primary_rays`). It hits part p at point x with the
   interpolated shading normal n turned towards the viewer; −1 elsewhere.
2. r = reflect(v, n) = v − 2 (v·n) n, v the unit ray direction.
3. The lookup vector q per model (§4, "EM Representations"; Figure 6):

   ========== ============================================================
   distant    x + t·r leaving the distant box, minus the part's EM origin
   local      x + t·r leaving the part's minimum-volume ellipsoid, minus
              the EM origin
   sphere     r (the sphere at infinity, direction only)
   ptm        x minus the EM origin: a surface texture, the same texel for
              a surface point from every view (seed 003 §6's PTM, Figure 7;
              not an EM: nothing is reflected)
   ========== ============================================================

   (a ray that would not leave its geometry, which cannot happen from inside
   it, falls back to q = r), and (face, (s, t)) = ``direction_to_uv(q)``
   (core/cubemap.py, OpenGL faces +X −X +Y −Y +Z −Z).
4. The level: with q̂ = q/|q| and Δ the difference of q̂ to the right (Δx) and
   lower (Δy) neighbour pixel — to the left / upper one where that neighbour's
   centre ray is not on the same part, 0 where neither is —
   ``lod = log2(n/2 · max(|Δx|, |Δy|))``, n the finest face edge (a face spans
   2 units of q̂'s tangent plane at distance 1, so n/2·|Δq̂| ≈ texels per pixel);
   a zero spread stores −64 (any clamp then gives level 0).

The trilinear lookup (:func:`trilinear_matrix`)
-----------------------------------------------
A bake adds its ``lod_bias`` (:data:`LOD_BIAS`) to the level of step 4 first.
Level k has n_k = n >> k, L levels (n >> (L − 1) ≥ 1). lod is clamped to
[0, L − 1]; l0 = ⌊lod⌋, l1 = min(l0 + 1, L − 1), w = lod − l0. At level k,
x = s·n_k − ½, y = t·n_k − ½, j0 = ⌊x⌋, i0 = ⌊y⌋, fx = x − j0, fy = y − i0; the
texels (i0 | i0 + 1, j0 | j0 + 1), each index clipped to [0, n_k − 1]
(``GL_CLAMP_TO_EDGE`` per face, no seam filtering), weigh (1 − fy | fy)·(1 − fx | fx)
— :func:`envstudio.methods.pem.bake.infer.cube_bilinear` per level. The row is
(1 − w)·bilinear(l0) + w·bilinear(l1). Column offset_k + face·n_k² + i·n_k + j,
offset_k = Σ_{j<k} 6·n_j² (:func:`envstudio.methods.pem.bake.mip.level_offsets`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from scipy import sparse

from envstudio.core.cubemap import direction_to_uv
from envstudio.methods.pem.bake.mip import level_offsets, mip_sizes
from envstudio.scene.camera import OrbitCamera

__all__ = [
    "CHANNELS",
    "LOD_BIAS",
    "MODELS",
    "PLAYBACK",
    "REQUIRED",
    "PixelLookups",
    "pixel_lookups",
    "trilinear_matrix",
]

#: The maps of a bake (seed 003 §4, Figures 6 and 7): the layered pair, the single
#: sphere at infinity, and the PTM's per-view surface texture (issue 31; §6 compares
#: PEMs with PTMs above the plane of samples). Bakes made before issue 31 have no
#: ``ptm`` maps (:data:`REQUIRED`).
MODELS = ("distant", "local", "sphere", "ptm")
#: The maps every ``.pem`` holds; the others are optional.
REQUIRED = ("distant", "local", "sphere")
#: Channels of each model's map: RGB; premultiplied RGBA for the local layer.
CHANNELS = {"distant": 3, "local": 4, "sphere": 3, "ptm": 3}
#: Level bias of a bake's lookups (``PixelLookups.matrix``; the ``.pem`` stores it as
#: ``parameters["lod_bias"]`` and the playback adds it to the level before the
#: clamp). −2 fits ``room`` best at 128² and 256² (studies/pem-bake/README.md): with every
#: level inferred, sampling two levels finer than one texel per pixel lets the solve
#: keep detail the trilinear filter of the unbiased level blurs.
LOD_BIAS = -2.0
#: The predicted playbacks compared with the traced composite (methods/pem/bake/models.py;
#: seed 003 Figures 1, 6 and 7): layered (local over distant), sphere at infinity, static EM,
#: the PTM's surface texture (absent from bakes made before issue 31).
PLAYBACK = ("layered", "sphere", "static", "ptm")


@dataclass
class PixelLookups:
    """The playback's EM lookups of one view, one per pixel (module docstring).

    Attributes
    ----------
    size : int
        R; arrays are R × R, row 0 at the top.
    em_size : int
        n, the finest face edge the levels were computed for.
    part : (R, R) int8
        Reflector part under the pixel centre, −1 for none.
    triangle : (R, R) int32
        The hit triangle's index in its part's mesh faces (the order the
        playback draws them, ``gl_PrimitiveID``), −1 for none.
    face, st, lod : dict of str
        Per model in :data:`MODELS`: face (R, R) int8 (−1 off the reflectors),
        st (R, R, 2) float32 cube-face (s, t), lod (R, R) float32 unclamped level.
    """

    size: int
    em_size: int
    part: npt.NDArray[np.int8]
    triangle: npt.NDArray[np.int32]
    face: dict[str, npt.NDArray[np.int8]] = field(default_factory=dict)
    st: dict[str, npt.NDArray[np.float32]] = field(default_factory=dict)
    lod: dict[str, npt.NDArray[np.float32]] = field(default_factory=dict)

    def matrix(
        self,
        model: str,
        part: int,
        levels: int | None = None,
        em_size: int | None = None,
        lod_bias: float = 0.0,
    ) -> sparse.csr_matrix:
        """(R², Σ 6 n_k²) :func:`trilinear_matrix` of ``model`` over the pixels of ``part``.

        ``em_size`` (default :attr:`em_size`) rescales the level by log2 of its ratio
        to :attr:`em_size`; ``lod_bias`` is added to every level before the clamp
        (the playback's ``lod_bias``).
        """
        on = np.flatnonzero(self.part.ravel() == part)
        n = self.em_size if em_size is None else int(em_size)
        lod = self.lod[model].ravel()[on] + np.log2(n / self.em_size) + float(lod_bias)
        return trilinear_matrix(
            on,
            self.face[model].ravel()[on],
            self.st[model].reshape(-1, 2)[on],
            lod,
            n,
            len(mip_sizes(n, levels)),
            self.size * self.size,
        )


def _bilinear(face, st, level, size):
    """(k, 4) texel index within the level and (k, 4) weights (module docstring)."""
    nk = (size >> level).astype(np.int64)
    x = st[:, 0] * nk - 0.5
    y = st[:, 1] * nk - 0.5
    j0, i0 = np.floor(x), np.floor(y)
    fx, fy = x - j0, y - i0
    j0, i0 = j0.astype(np.int64), i0.astype(np.int64)
    top = nk - 1
    jj = np.clip(np.stack([j0, j0 + 1]), 0, top)
    ii = np.clip(np.stack([i0, i0 + 1]), 0, top)
    base = face * nk * nk
    texels = np.stack([base + ii[a] * nk + jj[b] for a in (0, 1) for b in (0, 1)], axis=1)
    wx, wy = np.stack([1 - fx, fx]), np.stack([1 - fy, fy])
    weights = np.stack([wy[a] * wx[b] for a in (0, 1) for b in (0, 1)], axis=1)
    return texels, weights


def trilinear_matrix(
    pixel: npt.ArrayLike,
    face: npt.ArrayLike,
    st: npt.ArrayLike,
    lod: npt.ArrayLike,
    size: int,
    levels: int,
    npix: int,
    weight: npt.ArrayLike | None = None,
) -> sparse.csr_matrix:
    """The rendering matrix of trilinear cube-map lookups (module docstring).

    Parameters
    ----------
    pixel
        (M,) int, the row (pixel) of each lookup; several lookups may share one.
    face
        (M,) int, cube face 0..5.
    st
        (M, 2) float, face coordinates (s, t) in [0, 1].
    lod
        (M,) float, MIP level (clamped to [0, L − 1]).
    size
        n, the finest face edge.
    levels
        L, with n >> (L − 1) ≥ 1.
    npix
        Rows of the matrix.
    weight
        (M,) float per-lookup weight (default 1): a pixel's row is the weighted
        sum of its lookups' trilinear weights.

    Returns
    -------
    (npix, Σ_k 6·n_k²) scipy.sparse.csr_matrix
        Duplicates summed; a pixel with one lookup of weight 1 has a row summing to 1.
    """
    pixel = np.asarray(pixel, dtype=np.int64).ravel()
    face = np.asarray(face, dtype=np.int64).ravel()
    st = np.asarray(st, dtype=np.float64).reshape(-1, 2)
    lod = np.asarray(lod, dtype=np.float64).ravel()
    m = len(pixel)
    if not (len(face) == len(st) == len(lod) == m):
        raise ValueError(
            f"lookups of different lengths: pixel {m}, face {len(face)}, st {len(st)}, "
            f"lod {len(lod)}"
        )
    if m and (face.min() < 0 or face.max() > 5):
        raise ValueError("cube faces must be in 0..5")
    offsets = level_offsets(size, levels)
    w = np.ones(m) if weight is None else np.asarray(weight, dtype=np.float64).ravel()
    lod = np.clip(np.nan_to_num(lod, nan=0.0), 0.0, levels - 1)
    l0 = np.floor(lod).astype(np.int64)
    l1 = np.minimum(l0 + 1, levels - 1)
    frac = lod - l0
    cols, vals = [], []
    for level, share in ((l0, 1.0 - frac), (l1, frac)):
        texels, weights = _bilinear(face, st, level, size)
        cols.append(texels + offsets[level][:, None])
        vals.append(weights * (share * w)[:, None])
    rows = np.tile(np.repeat(pixel, 4), 2)
    a = sparse.coo_matrix(
        (
            np.concatenate([v.ravel() for v in vals]),
            (rows, np.concatenate([c.ravel() for c in cols])),
        ),
        shape=(npix, int(offsets[-1])),
    ).tocsr()
    a.sum_duplicates()
    a.eliminate_zeros()
    return a


def _level(q_hat: np.ndarray, part: np.ndarray, n: int) -> np.ndarray:
    """(R, R) lod = log2(n/2 · max(|Δx|, |Δy|)) of unit lookups (module docstring)."""

    def delta(axis: int) -> np.ndarray:
        same_next = np.zeros(part.shape, bool)
        same_prev = np.zeros(part.shape, bool)
        nxt = np.zeros_like(q_hat)
        prv = np.zeros_like(q_hat)
        if axis == 1:
            same_next[:, :-1] = part[:, 1:] == part[:, :-1]
            nxt[:, :-1] = q_hat[:, 1:] - q_hat[:, :-1]
            same_prev[:, 1:] = part[:, 1:] == part[:, :-1]
            prv[:, 1:] = q_hat[:, 1:] - q_hat[:, :-1]
        else:
            same_next[:-1] = part[1:] == part[:-1]
            nxt[:-1] = q_hat[1:] - q_hat[:-1]
            same_prev[1:] = part[1:] == part[:-1]
            prv[1:] = q_hat[1:] - q_hat[:-1]
        d = np.where(same_next[..., None], nxt, np.where(same_prev[..., None], prv, 0.0))
        return np.linalg.norm(d, axis=-1)

    spread = np.maximum(delta(1), delta(0))
    with np.errstate(divide="ignore"):
        lod = np.log2(n / 2.0 * spread)
    return np.where(part >= 0, np.maximum(lod, -64.0), 0.0)


def pixel_lookups(
    tracer,
    camera: OrbitCamera,
    size: int,
    em_size: int,
    box,
    ellipsoids,
    origins: npt.ArrayLike,
) -> PixelLookups:
    """The playback's per-pixel lookups of one view, on the CPU (module docstring).

    Parameters
    ----------
    tracer
        The scene's :class:`~envstudio.methods.pem.bake.trace.SceneTracer`.
    camera
        The view.
    size
        R.
    em_size
        n, the finest face edge (the lod's scale).
    box
        The distant :class:`~envstudio.methods.pem.bake.infer.BoxGeometry`.
    ellipsoids
        P :class:`~envstudio.methods.pem.bake.infer.EllipsoidGeometry`, one per part.
    origins
        (P, 3) EM origins.

    Returns
    -------
    PixelLookups
    """
    _, o, d = tracer.centre_rays(camera, size)
    tri, t, u, v = tracer._intersect(False, o, d)
    part = np.where(tri >= 0, tracer.part[np.maximum(tri, 0)], -1)
    on = np.flatnonzero(part >= 0)
    origins = np.asarray(origins, dtype=np.float64).reshape(-1, 3)
    x = o[on] + t[on, None] * d[on]
    nrm = tracer._shading_normal(tri[on], u[on], v[on], d[on])
    r = d[on] - 2.0 * np.einsum("ij,ij->i", d[on], nrm)[:, None] * nrm
    p_on = part[on]
    npix = size * size
    triangle = np.full(npix, -1, np.int32)
    triangle[on] = tri[on] - tracer.part_start[p_on]
    out = PixelLookups(
        size=size,
        em_size=int(em_size),
        part=part.reshape(size, size).astype(np.int8),
        triangle=triangle.reshape(size, size),
    )
    part_img = out.part.astype(np.int64)
    for model in MODELS:
        if model == "sphere":
            q = r
        elif model == "ptm":
            q = x - origins[p_on]
            bad = np.linalg.norm(q, axis=1) == 0
            q[bad] = r[bad]
        else:
            q = np.empty_like(r)
            for p in np.unique(p_on):
                sel = p_on == p
                geometry = box if model == "distant" else ellipsoids[p]
                exit_t = geometry.exit_distance(x[sel], r[sel])
                qp = x[sel] + np.nan_to_num(exit_t)[:, None] * r[sel] - origins[p]
                bad = ~np.isfinite(exit_t) | (np.linalg.norm(qp, axis=1) == 0)
                qp[bad] = r[sel][bad]
                q[sel] = qp
        face = np.full(npix, -1, np.int8)
        st = np.zeros((npix, 2), np.float32)
        q_hat = np.zeros((npix, 3))
        if len(on):
            f, uv = direction_to_uv(q)
            face[on], st[on] = f, uv
            q_hat[on] = q / np.linalg.norm(q, axis=1, keepdims=True)
        out.face[model] = face.reshape(size, size)
        out.st[model] = st.reshape(size, size, 2)
        out.lod[model] = _level(q_hat.reshape(size, size, 3), part_img, em_size).astype(np.float32)
    return out
