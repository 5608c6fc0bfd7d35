"""The split sum's second factor: the DFG table of scale and bias of F0 (GL-free, NumPy).

Karis (SIGGRAPH 2013 course, "Real Shading in Unreal Engine 4", eq. 3 and its
"environment BRDF") splits the GGX specular integral into the prefiltered radiance
(prefilter.chain_gpu) times the directional albedo of the BRDF in a white
environment. With Schlick's F = F0 + (1 − F0) F_c, F_c = (1 − v·h)⁵, that albedo is
linear in F0:

    E(n·v, α) = ∫ f(l, v) (n·l) dl = F0 · A + B,
    A = ∫ (1 − F_c) G_vis,   B = ∫ F_c G_vis,

with G_vis = G2 (v·h) / ((n·h)(n·v)) the weight of a half vector h drawn in
proportion to D(h)(n·h) (core.ggx: GGX D, height-correlated Smith G2, the
reference's ``model=microfacet``). :func:`dfg_entries` estimates A and B by that
importance sampling, with one Hammersley set of :data:`SAMPLES` points for every
entry; :func:`dfg_table` tabulates them on (n·v, √α) and is computed once and
cached (:func:`load_dfg_table`). The rows are spaced in √α, the perceptual
roughness, as Filament's table is, because E changes fastest at small α.
:func:`dfg_quadrature` is the independent check: a deterministic Gauss–Legendre
rule over the half-vector hemisphere.

A + B is the white conductor's albedo (F0 = 1): less than one, since one
bounce between the microfacets is all the model keeps. Fdez-Agüera (JCGT 8(1),
2019) and Filament scale the single-scattering lobe by 1 + F0 (1/(A + B) − 1)
to give back the energy of the further bounces (:func:`energy_compensation`).
"""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path

import numpy as np
import numpy.typing as npt

from envstudio.core import ggx
from envstudio.errors import OutputFileError
from envstudio.io.atomic import atomic_path
from envstudio.io.cache_entries import discard
from envstudio.io.cache_folder import cache_folder
from envstudio.plugin import InputFileError

__all__ = [
    "SAMPLES",
    "TABLE_SIZE",
    "cache_dir",
    "dfg_entries",
    "dfg_quadrature",
    "dfg_table",
    "energy_compensation",
    "load_dfg_table",
    "lookup",
]

#: Entries per axis of the table (n·v columns, √α rows), texel centres at (i + ½)/size.
TABLE_SIZE = 64
#: Importance samples per entry (one Hammersley set shared by every entry).
SAMPLES = 16384
#: Part of the cache key: raise it when the estimator changes.
_VERSION = 1


def _hammersley(count: int) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(i + ½)/S and the base-2 radical inverse of i: S points of [0, 1)²."""
    i = np.arange(count, dtype=np.uint64)
    bits = np.zeros(count, dtype=np.float64)
    scale = 0.5
    k = i.copy()
    while np.any(k):
        bits += (k & np.uint64(1)).astype(np.float64) * scale
        k >>= np.uint64(1)
        scale *= 0.5
    return (np.arange(count) + 0.5) / count, bits


def _half_vector_terms(n_dot_v, alpha, u, phi):
    """G_vis and F_c for half vectors at CDF value u and azimuth phi (broadcast)."""
    nv = np.asarray(n_dot_v, dtype=np.float64)
    cos_h = ggx.half_vector_cosine(u, alpha)
    sin_h = np.sqrt(np.maximum(0.0, 1.0 - cos_h * cos_h))
    # v = (√(1 − nv²), 0, nv); h = (sin cos φ, sin sin φ, cos)
    v_dot_h = np.sqrt(np.maximum(0.0, 1.0 - nv * nv)) * sin_h * np.cos(phi) + nv * cos_h
    n_dot_l = 2.0 * v_dot_h * cos_h - nv
    lit = (n_dot_l > 0.0) & (v_dot_h > 0.0)
    g2 = ggx.smith_g2(n_dot_l, nv, alpha)
    g_vis = np.where(lit, g2 * v_dot_h / (np.maximum(cos_h, 1e-300) * nv), 0.0)
    f_c = (1.0 - np.clip(v_dot_h, 0.0, 1.0)) ** 5
    return g_vis, f_c


def dfg_entries(
    n_dot_v: npt.ArrayLike, alpha: float, samples: int = SAMPLES
) -> npt.NDArray[np.float64]:
    """A and B at cosines n·v for one α, by importance sampling D(h)(n·h).

    Parameters
    ----------
    n_dot_v
        (m,) cosines in (0, 1].
    alpha
        GGX α in (0, 1].
    samples
        S, points of the Hammersley set.

    Returns
    -------
    (m, 2) float64
        Scale A and bias B of F0 (module docstring).
    """
    nv = np.asarray(n_dot_v, dtype=np.float64).reshape(-1, 1)
    u, v = _hammersley(samples)
    g_vis, f_c = _half_vector_terms(nv, alpha, u[None, :], 2.0 * np.pi * v[None, :])
    return np.stack([((1.0 - f_c) * g_vis).mean(1), (f_c * g_vis).mean(1)], axis=1)


def dfg_quadrature(n_dot_v: float, alpha: float, nodes: int = 256) -> tuple[float, float]:
    """A and B at one (n·v, α) by a Gauss–Legendre rule: the check of :func:`dfg_entries`.

    The integral over half vectors, ∫ G_vis F D(h)(n·h) dh, is taken in the
    variables u (the CDF of D(h)(n·h) in θ_h) and φ, both on a ``nodes``-point
    Gauss–Legendre rule (φ over [0, π], the integrand being even in φ).

    Returns
    -------
    (float, float)
        A and B.
    """
    x, w = np.polynomial.legendre.leggauss(nodes)
    u, wu = 0.5 * (x + 1.0), 0.5 * w
    phi, wphi = 0.5 * np.pi * (x + 1.0), 0.5 * np.pi * w
    g_vis, f_c = _half_vector_terms(n_dot_v, alpha, u[:, None], phi[None, :])
    weights = wu[:, None] * wphi[None, :] / np.pi
    return float(np.sum(weights * (1.0 - f_c) * g_vis)), float(np.sum(weights * f_c * g_vis))


def dfg_table(size: int = TABLE_SIZE, samples: int = SAMPLES) -> npt.NDArray[np.float32]:
    """The table: [i, j] = (A, B) at n·v = (j + ½)/size, α = ((i + ½)/size)².

    Returns
    -------
    (size, size, 2) float32
        Rows in √α, columns in n·v, as the shader's texture (row 0 first).
    """
    centres = (np.arange(size) + 0.5) / size
    return np.stack([dfg_entries(centres, r * r, samples) for r in centres]).astype(np.float32)


def lookup(table: npt.NDArray[np.float32], n_dot_v: float, alpha: float) -> tuple[float, float]:
    """(A, B) at (n·v, α) by bilinear interpolation between texel centres, as the shader reads.

    Clamped at the edges (the texture's CLAMP_TO_EDGE).
    """
    size = table.shape[0]

    def coordinate(t: float) -> tuple[int, int, float]:
        x = min(max(t * size - 0.5, 0.0), size - 1.0)
        i = min(int(x), size - 2)
        return i, i + 1, x - i

    j0, j1, fx = coordinate(float(n_dot_v))
    i0, i1, fy = coordinate(float(np.sqrt(alpha)))
    top = (1.0 - fx) * table[i0, j0] + fx * table[i0, j1]
    bottom = (1.0 - fx) * table[i1, j0] + fx * table[i1, j1]
    a, b = (1.0 - fy) * top + fy * bottom
    return float(a), float(b)


def energy_compensation(f0: float, a: float, b: float) -> float:
    """Fdez-Agüera's factor as Filament writes it: 1 + F0 (1/(A + B) − 1)."""
    return 1.0 + f0 * (1.0 / (a + b) - 1.0)


def cache_dir() -> Path:
    """The table's cache folder: ``splitsum`` in envstudio's (:func:`.cache_folder`)."""
    return cache_folder("splitsum")


def load_dfg_table(size: int = TABLE_SIZE, samples: int = SAMPLES) -> npt.NDArray[np.float32]:
    """The table from the cache, computed (about a second) and saved atomically when missing.

    An entry that does not load or has the wrong shape is one note and computed again.
    """
    key = hashlib.sha256(f"dfg {_VERSION} {size} {samples}".encode()).hexdigest()[:16]
    path = cache_dir() / f"dfg-{size}-{key}.npy"
    if path.exists():
        try:
            table = np.load(path, allow_pickle=False)
            if table.shape != (size, size, 2) or table.dtype != np.float32:
                raise InputFileError(f"{path}: not a {size}x{size} DFG table")
            return table
        except (OSError, ValueError, InputFileError) as error:
            print(f"envstudio: note: {error}; discarded, computed again", file=sys.stderr)
            discard(path)
    table = dfg_table(size, samples)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path, need=table.nbytes) as tmp, open(tmp, "wb") as f:
            np.save(f, table)
    except (OSError, OutputFileError) as error:  # read-only cache: a second lost next time
        print(f"envstudio: note: DFG table not cached ({error})", file=sys.stderr)
    return table
