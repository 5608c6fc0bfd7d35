"""Brute-force integrals of a lat-long environment: the independent references.

Every function sums over all texels of a (downsampled) lat-long map with their
exact solid angles (core.latlong.texel_solid_angles), in chunks so memory stays
bounded. :func:`irradiance`, :func:`phong` and :func:`microfacet` are float64
and simple on purpose: tests and the glossiness fit compare the GPU estimators
and the hardware approximations against them. :func:`prefilter` is the brute
force of seed 004 §5.1 ("for every pixel in the target environment map, the
filter is applied to every single pixel in the source environment map") for a
whole target map: float32, chunked over target texels on every core, with a
progress bar; tests check it against the float64 sums.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.core import latlong
from envstudio.core.env_sampling import box_downsample
from envstudio.prefilter.kernels import Kernel
from envstudio.prefilter.parallel import run_chunks

_CHUNK = 2048
# prefilter(): target texels per thread task, and per block of one task (the block's
# (block, source texels) float32 cosines stay in the cache: 16 × 32768 × 4 B = 2 MiB).
_TASK = 256
_BLOCK = 16
# Source texels per piece: larger maps are summed piece by piece to stay in the cache.
_SOURCE_PIECE = 32768


def downsample_latlong(image: npt.ArrayLike, height: int) -> npt.NDArray[np.float64]:
    """Box-filter an (h, 2h, 3) map to (height, 2·height, 3); h must be a multiple of height."""
    img = np.asarray(image, dtype=np.float64)
    if img.shape[0] % height:
        raise ValueError(f"map height {img.shape[0]} is not a multiple of {height}")
    factor = img.shape[0] // height
    return box_downsample(img, factor) if factor > 1 else img


def _texels(image: npt.ArrayLike):
    img = np.asarray(image, dtype=np.float64)
    h, w = img.shape[:2]
    dirs = latlong.texel_directions(h, w).reshape(-1, 3)
    weighted = img.reshape(-1, 3) * latlong.texel_solid_angles(h, w).reshape(-1, 1)
    return dirs, weighted


def prefilter(
    image: npt.ArrayLike,
    directions: npt.ArrayLike,
    kernel: Kernel,
    *,
    threads: int | None = None,
    progress: bool = False,
) -> npt.NDArray[np.float32]:
    """Brute-force prefiltered map E(r) = Σ_s k(⟨r, l_s⟩) L_s Δω_s over every source texel.

    The discrete form of seed 004 §4's L_diffuse, L_phong and L_isotropic (2D):
    the kernel (prefilter.kernels) weighted by each texel's exact solid angle
    Δω_s (core.latlong.texel_solid_angles). Cosines and kernel in float32, the
    sums by BLAS in float32 blocks of 16 targets × all source texels.

    Parameters
    ----------
    image
        (h, w, 3) lat-long radiance (the source L_i).
    directions
        (..., 3) unit target directions (r for Phong and lobes, n for diffuse).
    kernel
        The filter.
    threads
        Worker threads (default: every core).
    progress
        Show a progress bar with the time left on stderr.

    Returns
    -------
    (..., 3) float32
        Prefiltered radiance at ``directions``.
    """
    dirs, weighted = _texels(image)
    src = np.ascontiguousarray(dirs.T, dtype=np.float32)
    weights_t = np.ascontiguousarray(weighted.T, dtype=np.float32)
    q = np.asarray(directions, dtype=np.float32)
    flat = q.reshape(-1, 3)
    out = np.empty((len(flat), 3), np.float32)
    starts = range(0, len(flat), _TASK)

    pieces = [slice(s, s + _SOURCE_PIECE) for s in range(0, src.shape[1], _SOURCE_PIECE)]

    def work(k: int) -> None:
        start = starts[k]
        stop = min(start + _TASK, len(flat))
        cos = np.empty((_BLOCK, min(_SOURCE_PIECE, src.shape[1])), np.float32)
        sums = np.zeros((stop - start, 3), np.float32)
        for piece in pieces:
            for b in range(start, stop, _BLOCK):
                block = flat[b : min(b + _BLOCK, stop)]
                c = cos[: len(block), : src[0, piece].size]
                cosines_into(block, src[:, piece], c)
                sums[b - start : b - start + len(block)] += weighted_sums(
                    kernel.shape_inplace(c), weights_t[:, piece]
                )
        out[start:stop] = sums * np.float32(kernel.scale)

    run_chunks(
        work,
        [min(_TASK, len(flat) - s) for s in starts],
        threads=threads,
        progress=progress,
        desc="brute force",
    )
    return out.reshape(*q.shape[:-1], 3)


def cosines_into(queries: np.ndarray, sources: np.ndarray, out: np.ndarray) -> np.ndarray:
    """⟨q, d⟩ for (m, 3) float32 queries and (3, n) float32 sources into (m, n) float32 ``out``.

    One BLAS product; with BLAS on one thread (prefilter.parallel) it runs at
    about a nanosecond per pair, several times the speed of broadcast multiply-adds.
    """
    return np.dot(queries, sources, out=out)


def weighted_sums(values: np.ndarray, weights_t: np.ndarray) -> np.ndarray:
    """(m, n) float32 filter values times (3, n) float32 weights → (m, 3): Σ_n F W.

    Written as (Wᵀ Fᵀ)ᵀ: OpenBLAS is about ten times faster on that shape than
    on F @ W with its inner dimension of n and three columns.
    """
    return (weights_t @ values.T).T


def _kernel_sum(image, queries, kernel) -> npt.NDArray[np.float64]:
    dirs, weighted = _texels(image)
    q = np.asarray(queries, dtype=np.float64)
    flat = q.reshape(-1, 3)
    out = np.empty((len(flat), 3))
    for start in range(0, len(flat), _CHUNK):
        cos = flat[start : start + _CHUNK] @ dirs.T
        out[start : start + _CHUNK] = kernel(cos) @ weighted
    return out.reshape(*q.shape[:-1], 3)


def irradiance(image: npt.ArrayLike, normals: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """E(n) = ∫ L(l) max(n·l, 0) dl for (..., 3) unit normals (seed 000 eq. 4 without k_d/π)."""
    return _kernel_sum(image, normals, lambda c: np.maximum(c, 0.0))


def phong(
    image: npt.ArrayLike, reflections: npt.ArrayLike, exponent: float
) -> npt.NDArray[np.float64]:
    """Normalised Phong lobe of seed 000 eq. 7, L(r) = (N+1)/2π ∫ max(r·l, 0)^N L(l) dl.

    The normalisation (N + 1)/2π makes the lobe integrate to 1 over the
    hemisphere about r, so a constant environment L gives L.
    """
    scale = (exponent + 1.0) / (2.0 * np.pi)
    return _kernel_sum(image, reflections, lambda c: scale * np.maximum(c, 0.0) ** exponent)


def microfacet(
    image: npt.ArrayLike,
    normals: npt.ArrayLike,
    views: npt.ArrayLike,
    alpha: float,
    f0: float,
    kd: float,
) -> npt.NDArray[np.float64]:
    """Exitant radiance of the reference's microfacet model, summed over every texel.

    f = k_d/π (1 − F(n·v)) + D G2 F(v·h) / (4 (n·l)(n·v)), with GGX D, the
    height-correlated Smith G2 and Schlick F of ``f0`` (shaders/reference/
    sampling.glsl, accumulate.glsl), integrated against L(l) (n·l) over n·l > 0.

    Parameters
    ----------
    image
        (h, 2h, 3) lat-long radiance.
    normals, views
        (..., 3) unit normals and unit directions towards the eye.
    alpha
        GGX roughness.
    f0, kd
        Schlick reflectance at normal incidence and diffuse albedo.

    Returns
    -------
    (..., 3) float64
        Radiance towards ``views``.
    """
    dirs, weighted = _texels(image)
    n = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    v = np.asarray(views, dtype=np.float64).reshape(-1, 3)
    out = np.empty((len(n), 3))
    a2 = alpha * alpha
    for start in range(0, len(n), _CHUNK // 4):
        nc, vc = n[start : start + _CHUNK // 4], v[start : start + _CHUNK // 4]
        n_dot_l = nc @ dirs.T
        n_dot_v = np.maximum(np.sum(nc * vc, -1, keepdims=True), 1e-4)
        h = vc[:, None, :] + dirs[None, :, :]
        h /= np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-12)
        n_dot_h = np.maximum(np.einsum("qk,qtk->qt", nc, h), 0.0)
        v_dot_h = np.maximum(np.einsum("qk,qtk->qt", vc, h), 1e-4)
        d = a2 / (np.pi * (n_dot_h**2 * (a2 - 1.0) + 1.0) ** 2)
        lit = np.maximum(n_dot_l, 0.0)
        g_l = n_dot_v * np.sqrt(lit**2 * (1.0 - a2) + a2)
        g_v = lit * np.sqrt(n_dot_v**2 * (1.0 - a2) + a2)
        g2 = 2.0 * lit * n_dot_v / np.maximum(g_l + g_v, 1e-9)
        fresnel = f0 + (1.0 - f0) * (1.0 - v_dot_h) ** 5
        specular = d * g2 * fresnel / (4.0 * np.maximum(lit, 1e-9) * n_dot_v)
        diffuse = kd / np.pi * (1.0 - (f0 + (1.0 - f0) * (1.0 - n_dot_v) ** 5))
        f = np.where(n_dot_l > 0.0, (specular + diffuse) * lit, 0.0)
        out[start : start + _CHUNK // 4] = f @ weighted
    return out.reshape(*np.shape(normals)[:-1], 3)
