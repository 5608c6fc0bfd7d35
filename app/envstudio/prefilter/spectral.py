"""The Phong prefilter of a lat-long map by rows and azimuthal frequencies: exact and fast.

The brute force (prefilter.brute_force.prefilter, seed 004 §5.1) sums, for a target
direction r = (θ, φ) and every source texel l = (θ_l, φ_j) of solid angle Δω_l,

    E(r) = Σ_l Σ_j k(⟨r, l⟩) L_lj Δω_l,   ⟨r, l⟩ = cos θ cos θ_l + sin θ sin θ_l cos(φ − φ_j),

with k the normalised Phong lobe (N + 1)/2π max(c, 0)^N of seed 004 §4. For a fixed pair
of rows (θ, θ_l) the kernel is a function of φ − φ_j alone, so the sum over a source row
is a circular convolution along the row: with g_{θ,l}(Δφ) = k(⟨r, l⟩) and its Fourier
coefficients ĝ_m, and X_lm the DFT of source row l,

    E(θ, φ) = Σ_l Δω_l Σ_m ĝ_{θ,l,m} X_lm e^{−iπm/w} e^{imφ'}     (φ' = 2πu, u as core.latlong)

(the phase: source column j sits at u = (j + ½)/w). This is the brute force rewritten,
with no approximation of the kernel (true cos^N, not a Gaussian): what is left out is
where it is negligible, each bounded by ``eps`` of the lobe's peak:

- source rows farther than Θ from θ, cos^N Θ = eps (the angle to any texel of a row is
  at least the difference of the rows' θ);
- frequencies m above m_max, where |ĝ_m| < eps ĝ_0 for the narrowest row pair in φ (the
  equator's); for m ≥ w/2 (lobes narrower than a column) X_m = X_{m mod w}, the DFT being
  periodic, so the sum over texel centres stays exact;
- ĝ is the DFT of g sampled at W' ≥ 2 (m_max + 1) points of Δφ: aliased by ĝ beyond m_max.

E is computed on an (R, W_out) lat-long grid of spacing at most about 0.42 N^−½ (two fifths of
the lobe's width; E is a sum of such lobes, smooth at that scale), its rows R = h / q every
q-th source row boundary (q a divisor of h), or R = h p, p rows per source row, when the
source is coarser than that, so that grid row i reads source rows q·⌊i/p⌋ + off + s, a
strided view: one batched matrix product per level), and read at the target
directions by cubic B-spline interpolation. The spline's prefilter is done on the spectrum:
along φ it is a division by the B-spline's response (2 + cos ω)/3 (periodic), along θ
Unser's recursion (:func:`_prefilter_rows`) over the grid padded across the poles (row
−1 − j is row j turned by half a turn: coefficient m times (−1)^m); the B-spline basis at
the targets is a cached sparse matrix. In a chain, level 0 (about half the work) runs on
one thread and the other levels on the rest (:func:`spectral_chain`).

The same sums hold for any kernel of ⟨r, l⟩ alone; :func:`ggx_spectral_chain` uses them for
the split-sum GGX lobe (prefilter.kernels.ggx, N = V = R) with the lobe's width set by α
(σ ≈ α near the peak, so N = 1/α² for the grid spacing) and Θ where the lobe falls to
``eps`` of its peak, found numerically: GGX's tails are long (at α = 0.02 Θ is some 40°,
at α ≥ 0.1 the hemisphere), so m_max is found by doubling the equator's sampling until
its spectrum has fallen below ``eps`` well inside it.

Cost per map, for a source of h rows: the source's row DFTs once (shared by every level
of a chain), then R × (rows within Θ) × m_max complex multiply-adds per channel, which
falls as N^−½ with the lobe's width (R and m_max grow as N^½, the rows within Θ shrink as
N^−½), then the interpolation, linear in the target texels. The per-level tables
(:func:`plan`: ĝ for every row pair) depend on the source's shape and N only and are
cached, as a GPU program is compiled once (measured cold and warm in
studies/prefilter-speed/README.md).
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import numpy.typing as npt
import scipy.fft
from numpy.lib.stride_tricks import as_strided
from scipy import sparse

from envstudio.core import cubemap, latlong, resample
from envstudio.prefilter import kernels, roughness
from envstudio.prefilter.chain import ChainLevel, gloss_exponents

__all__ = [
    "DEFAULT_EPS",
    "SpectralPlan",
    "clear_lookups",
    "ggx_spectral_chain",
    "lobe_at",
    "phong_spectral",
    "plan",
    "source_spectrum",
    "spectral_chain",
]

#: Relative size, to the lobe's peak, of every term left out (module docstring).
DEFAULT_EPS = 1e-5
#: Largest grid spacing over the lobe's width N^−½ (module docstring).
_SPACING = 0.42
#: Rows added across each pole and columns around the seam, for the spline.
_PAD = 8
#: Pieces a level's product is cut into when :func:`phong_spectral` is given threads.
_POOL_PARTS = 2


@dataclass(frozen=True)
class SpectralPlan:
    """The per-level tables of :func:`phong_spectral` (module docstring).

    Attributes
    ----------
    exponent
        N (``kernel`` "phong") or GGX α ("ggx").
    source_shape
        (h, w) of the source.
    stride, split
        q and p: the grid has R = h p / q rows (q = 1 or p = 1), row i centred at
        θ = π (i + ½) / R.
    offset
        Grid row i reads source rows q ⌊i / p⌋ + offset + s, s = 0 … S − 1 (rows outside
        the map have weight 0).
    weights
        (R, m_max + 1, 1, S) float32: Δω_l ĝ_{θ,l,m} of source row q ⌊i / p⌋ + offset + s.
    grid_cols
        W_out, columns of the grid of E.
    """

    exponent: float
    source_shape: tuple[int, int]
    stride: int
    split: int
    offset: int
    weights: np.ndarray
    grid_cols: int
    kernel: str = "phong"

    @property
    def frequencies(self) -> int:
        """m_max + 1."""
        return self.weights.shape[1]

    @property
    def grid_rows(self) -> int:
        """R."""
        return self.weights.shape[0]

    @property
    def span(self) -> int:
        """S, source rows read per grid row."""
        return self.weights.shape[3]


def _phong(exponent: float, c: np.ndarray) -> np.ndarray:
    """(N + 1)/2π max(c, 0)^N, float32, as exp(N ln c) floored at e^−80 like the brute force
    (N = 1, the cosine lobe, directly)."""
    if exponent == 1.0:
        return np.maximum(c, np.float32(0.0), dtype=np.float32) * np.float32(1.0 / math.pi)
    out = np.log(np.maximum(c, np.float32(1e-30)), dtype=np.float32)
    out *= np.float32(exponent)
    np.maximum(out, np.float32(-80.0), out=out)
    np.exp(out, out=out)
    out *= np.float32((exponent + 1.0) / (2.0 * math.pi))
    return out


def _ggx(alpha: float, c: np.ndarray) -> np.ndarray:
    """The normalised split-sum GGX lobe k(c) of prefilter.kernels.ggx, in c's dtype."""
    kernel = kernels.ggx(alpha)
    a2 = alpha * alpha
    c = np.maximum(c, 0.0)
    denominator = (1.0 - c) * 0.5 * (1.0 - a2) + a2
    return (kernel.scale * a2 * a2 * c / (denominator * denominator)).astype(c.dtype)


def _lobe_width(kernel: str, parameter: float, eps: float) -> tuple[float, float]:
    """(N, Θ): the Phong exponent that sets the grid spacing, and the angle past which the
    lobe is below ``eps`` of its peak (module docstring)."""
    if kernel == "phong":
        return parameter, min(math.acos(eps ** (1.0 / parameter)), 0.5 * math.pi)
    theta = np.linspace(0.0, 0.5 * math.pi, 4097)
    shape = _ggx(parameter, np.cos(theta)) / _ggx(parameter, np.ones(1))[0]
    inside = np.nonzero(shape >= eps)[0]
    return 1.0 / parameter**2, float(theta[min(inside[-1] + 1, len(theta) - 1)])


def _stride(height: int, wanted_rows: int) -> int:
    """q: the largest divisor of h with h / q ≥ the rows wanted (1 if h has fewer)."""
    best = 1
    for q in range(1, height + 1):
        if height % q == 0 and height // q >= wanted_rows:
            best = q
    return best


@lru_cache(maxsize=32)
def plan(
    height: int,
    width: int,
    exponent: float,
    eps: float = DEFAULT_EPS,
    kernel: str = "phong",
    min_rows: int = 16,
    oversample: float = 1.0,
    footprint: bool = False,
) -> SpectralPlan:
    """The tables for a Phong exponent N (or a GGX α, ``kernel="ggx"``) and an (h, w)
    lat-long source (module docstring); the grid has at least ``min_rows`` rows and
    ``oversample`` times the rows its spacing asks for (a finer grid interpolates more
    closely: N = 1's max(c, 0) has a kink).

    With ``footprint`` each texel's weight is the lobe integrated over the texel, not the
    lobe at its centre times its solid angle: the integral of the map as a function
    constant over each texel (what a renderer that samples directions and reads the texel
    there converges to), exact however narrow the lobe against the texels. Along φ that is
    the box filter of the column's width, ĝ_m · sinc(m Δφ / 2) on the spectrum; along θ
    each row is cut into sub-rows (each at most a quarter of the lobe's width, N^−½, or of
    a half radian) integrated by three Gauss–Legendre points weighed by sin θ.

    Cached: they depend on the source's shape, the kernel, N (α), the grid's rows and
    ``footprint`` only.
    """
    if kernel not in ("phong", "ggx"):
        raise ValueError(f"kernel {kernel!r}: expected 'phong' or 'ggx'")
    if not exponent > 0:
        raise ValueError(f"Phong exponent or GGX alpha must be > 0, got {exponent}")
    width_n, theta_max = _lobe_width(kernel, exponent, eps)
    # Frequencies: the narrowest row pair in φ is the equator's, g(Δφ) = k(cos Δφ) (float64:
    # float32 rounding alone is above 1e-6 of the peak's spectrum), sampled finely enough
    # for its spectrum down to eps whatever the source's columns.
    reach = math.sqrt(2.0 * width_n * math.log(1.0 / eps)) + 16.0
    fine = max(width, 1 << math.ceil(math.log2(4.0 * reach)))
    while True:
        cos_dphi = np.cos(2.0 * math.pi * np.arange(fine) / fine)
        if kernel == "phong":
            equator = np.where(cos_dphi > 0, np.maximum(cos_dphi, 1e-300) ** exponent, 0.0)
        else:
            equator = _ggx(exponent, cos_dphi)
        spectrum = np.abs(np.fft.rfft(equator))
        above = np.nonzero(spectrum > eps * spectrum[0])[0]
        m_max = int(above[-1] if len(above) else 0)
        if kernel == "phong" or 4 * m_max < fine:
            break
        fine *= 2
    samples = max(64, 1 << math.ceil(math.log2(2 * (m_max + 1))))
    # Rows: source rows within Θ of the grid row (the lobe below eps of its peak past Θ).
    # The grid has R = h p / q rows: every q-th source row boundary (q | h) or p rows per
    # source row when h is short.
    wanted = max(min_rows, math.ceil(oversample * math.pi * math.sqrt(width_n) / _SPACING))
    if wanted <= height:
        q, p = _stride(height, wanted), 1
    else:
        q, p = 1, math.ceil(wanted / height)
    grid_rows = height * p // q
    grid_cols = scipy.fft.next_fast_len(max(math.ceil(2.0 * wanted), 2 * m_max + 2), real=True)
    grid_cols += grid_cols % 2
    row_angle = math.pi / height
    # Grid row i = t p + r is centred at source-row coordinate t q + (r + ½) q / p and reads
    # source rows t q + offset + s.
    offset = math.floor(0.5 * q / p - 0.5 - theta_max / row_angle)
    last = math.floor((p - 0.5) * q / p - 0.5 - theta_max / row_angle)
    span = math.ceil(2.0 * theta_max / row_angle) + 2 + (last - offset)
    i = np.arange(grid_rows)
    theta = math.pi * (i + 0.5) / grid_rows
    source_row = q * (i // p)[:, None] + offset + np.arange(span)[None, :]
    inside = (source_row >= 0) & (source_row < height)
    row = np.clip(source_row, 0, height - 1)
    # g is even in Δφ: its DFT over ``samples`` points is the DCT-I of the first half.
    cos_t = np.cos(2.0 * math.pi * np.arange(samples // 2 + 1) / samples).astype(np.float32)
    lobe = _phong if kernel == "phong" else _ggx
    # With the footprint, each source row as ``cuts`` sub-rows of Gauss points in θ.
    cuts = min(64, max(1, math.ceil(4.0 * row_angle * math.sqrt(max(width_n, 16.0)))))
    # The midpoint rule's relative error over a texel's θ-band, (Δθ)² N / 24: where it is
    # negligible the texel's centre serves (N = 1 on a fine map), else the Gauss sub-rows.
    midpoint = row_angle**2 * width_n / 24.0 < _MIDPOINT_ERROR
    quadrature = cuts if footprint and not midpoint else 0
    g = np.zeros((*row.shape, len(cos_t)), np.float32)
    for theta_l, solid_angle in _row_quadrature(row, height, width, quadrature):
        cos_part = (np.cos(theta)[:, None] * np.cos(theta_l)).astype(np.float32)
        sin_part = (np.sin(theta)[:, None] * np.sin(theta_l)).astype(np.float32)
        part = lobe(exponent, cos_part[..., None] + sin_part[..., None] * cos_t)
        part *= (solid_angle * inside / samples).astype(np.float32)[..., None]
        g += part
    weights = scipy.fft.dct(g, type=1, axis=-1, workers=-1)[..., : m_max + 1]
    if footprint:  # the column's box along φ: ĝ_m sinc(m Δφ / 2)
        weights *= np.sinc(np.arange(m_max + 1) / width).astype(np.float32)
    weights = np.ascontiguousarray(weights.transpose(0, 2, 1)[:, :, None, :], dtype=np.float32)
    return SpectralPlan(float(exponent), (height, width), q, p, offset, weights, grid_cols, kernel)


#: Below this relative error of the midpoint rule over a texel's θ-band the footprint's
#: integral takes the texel's centre (:func:`plan`).
_MIDPOINT_ERROR = 1e-6
#: Gauss–Legendre nodes and weights on [−1, 1] (three points: exact to degree 5).
_GAUSS = ((-math.sqrt(0.6), 5.0 / 9.0), (0.0, 8.0 / 9.0), (math.sqrt(0.6), 5.0 / 9.0))


def _row_quadrature(row: np.ndarray, height: int, width: int, cuts: int):
    """(θ, Δω) pairs whose sum Σ Δω g(θ) stands for source row ``row``'s θ-band integral of
    g times its column's width: the row's centre and solid angle (``cuts`` 0: the brute
    force's texel centre), or ``cuts`` sub-rows of three Gauss–Legendre points each in θ,
    weighed by sin θ (the integral over the texel)."""
    d_phi = 2.0 * math.pi / width
    if cuts == 0:
        top, bottom = math.pi * row / height, math.pi * (row + 1) / height
        yield 0.5 * (top + bottom), d_phi * (np.cos(top) - np.cos(bottom))
        return
    half = 0.5 * math.pi / (height * cuts)
    for k in range(cuts):
        middle = math.pi * (row + (k + 0.5) / cuts) / height
        for node, weight in _GAUSS:
            theta_l = middle + node * half
            yield theta_l, d_phi * weight * half * np.sin(theta_l)


def source_spectrum(radiance: npt.ArrayLike, frequencies: int) -> np.ndarray:
    """X_lm e^{−iπm/w}: each source row's DFT, the first ``frequencies`` terms.

    Parameters
    ----------
    radiance
        (h, w, 3) lat-long radiance.
    frequencies
        m_max + 1 of the widest plan it serves.

    Returns
    -------
    (h, frequencies, 3) complex64
    """
    image = np.asarray(radiance, dtype=np.float32)
    if image.ndim != 3 or image.shape[2] != 3:
        raise ValueError(f"radiance must have shape (h, w, 3), got {image.shape}")
    w = image.shape[1]
    if frequencies <= w // 2 + 1:
        spectrum = scipy.fft.rfft(image, axis=1, workers=-1)[:, :frequencies]
    else:
        # Lobes narrower than the source's columns: the sum over texel centres has every
        # frequency m, with X_m = X_{m mod w} (the DFT is periodic).
        full = scipy.fft.fft(image, axis=1, workers=-1)
        spectrum = full[:, np.arange(frequencies) % w]
    phase = np.exp(-1j * math.pi * np.arange(spectrum.shape[1]) / w)
    return (spectrum * phase[None, :, None]).astype(np.complex64)


def _padded_spectrum(spectrum: np.ndarray, plans: list[SpectralPlan]) -> tuple[np.ndarray, int]:
    """The spectrum as (before + h + after, m, 6) float32, zero rows around the map so that
    every plan's strided view stays inside; returns it and ``before``."""
    h = spectrum.shape[0]
    before = max(max(0, -p.offset) for p in plans)
    after = max(
        max(0, p.stride * (p.grid_rows // p.split - 1) + p.offset + p.span - h) for p in plans
    )
    m = max(p.frequencies for p in plans)
    x = np.zeros((before + h + after, m, 6), dtype=np.float32)
    x[before : before + h] = spectrum[:, :m].view(np.float32).reshape(h, m, 6)
    return x, before


def _grid_spectrum(
    padded: np.ndarray, before: int, level: SpectralPlan, pool: ThreadPoolExecutor | None
) -> np.ndarray:
    """Y_im = Σ_s weights · X over the rows read: (R, m_max + 1, 6) float32 (re, im × RGB).

    With a pool, the grid rows are shared out among its threads."""
    m, span, q, p = level.frequencies, level.span, level.stride, level.split
    start = padded[before + level.offset :, :m]
    rows_view = as_strided(
        start,
        (level.grid_rows // p, p, m, span, 6),
        (q * start.strides[0], 0, start.strides[1], start.strides[0], start.strides[2]),
        writeable=False,
    )
    weights = level.weights.reshape(level.grid_rows // p, p, m, 1, span)
    out = np.empty((level.grid_rows // p, p, m, 1, 6), dtype=np.float32)
    parts = 1 if pool is None else min(_POOL_PARTS, level.grid_rows // p)
    bounds = np.linspace(0, level.grid_rows // p, parts + 1).astype(int)

    def work(part: int) -> None:
        sl = slice(bounds[part], bounds[part + 1])
        np.matmul(weights[sl], rows_view[sl], out=out[sl])

    if parts > 1:
        list(pool.map(work, range(parts)))
    else:
        work(0)
    return out.reshape(level.grid_rows, m, 6)


def _spline_grid(y: np.ndarray, grid_cols: int) -> np.ndarray:
    """B-spline coefficients of E on the padded grid, (R + 2 pad, W_out + 2 pad, 3) float32."""
    m = y.shape[1]
    sign = np.where(np.arange(m) % 2, -1.0, 1.0).astype(np.float32)[None, :, None]
    rows = np.concatenate([y[_PAD - 1 :: -1] * sign, y, y[: -_PAD - 1 : -1] * sign])
    rows = _prefilter_rows(rows.reshape(rows.shape[0], -1)).reshape(rows.shape)
    response = (2.0 + np.cos(2.0 * math.pi * np.arange(m) / grid_cols)) / 3.0
    complex_rows = rows[..., 0::2] + 1j * rows[..., 1::2]
    complex_rows /= response[None, :, None]
    grid = scipy.fft.irfft(complex_rows, n=grid_cols, axis=1, workers=-1).astype(np.float32)
    grid *= np.float32(grid_cols)
    return np.concatenate([grid[:, -_PAD:], grid, grid[:, :_PAD]], axis=1)


def _prefilter_rows(x: np.ndarray) -> np.ndarray:
    """The cubic B-spline prefilter along axis 0 of a (K, C) float32 array (Unser's recursion).

    scipy.ndimage.spline_filter1d computes the same (mirror boundary) at about 25 ns an element
    here; this loops over the K rows with every row vectorised, some 5× faster at K ≈ 500.
    The causal start is the mirror sum over the first _PAD rows (the rest weigh below
    |z|^_PAD = 3·10⁻⁵, and they are pole padding, not read by any target).
    """
    z = np.float32(math.sqrt(3.0) - 2.0)
    c = np.empty_like(x)
    c[0] = (z ** np.arange(min(_PAD, len(x)), dtype=np.float32)) @ x[:_PAD]
    for k in range(1, len(x)):
        np.multiply(c[k - 1], z, out=c[k])
        c[k] += x[k]
    if len(x) > 1:
        c[-1] = (z / (z * z - 1)) * (c[-1] + z * c[-2])
    else:
        c[-1] *= z / (z * z - 1) * (1 + z)
    for k in range(len(x) - 2, -1, -1):
        np.subtract(c[k + 1], c[k], out=c[k])
        c[k] *= z
    c *= np.float32(6.0)
    return c


def _bspline(t: np.ndarray) -> list[np.ndarray]:
    """Cubic B-spline weights of nodes ⌊x⌋ − 1 … ⌊x⌋ + 2 for t = x − ⌊x⌋."""
    return [
        (1.0 - t) ** 3 / 6.0,
        (3.0 * t**3 - 6.0 * t**2 + 4.0) / 6.0,
        (-3.0 * t**3 + 3.0 * t**2 + 3.0 * t + 1.0) / 6.0,
        t**3 / 6.0,
    ]


@lru_cache(maxsize=16)
def _lookup(size: int, grid_rows: int, grid_cols: int) -> sparse.csr_matrix:
    """The B-spline basis at the cube texels of face n: (6 n², padded grid cells) sparse."""
    uv = latlong.direction_to_uv(cubemap.texel_directions(size)).reshape(-1, 2)
    return _basis(uv, grid_rows, grid_cols)


def _basis(uv: np.ndarray, grid_rows: int, grid_cols: int) -> sparse.csr_matrix:
    """The B-spline basis at lat-long coordinates ``uv`` (t, 2): (t, padded grid cells) sparse."""
    y = uv[:, 1] * grid_rows - 0.5 + _PAD
    x = uv[:, 0] * grid_cols + _PAD
    y0, x0 = np.floor(y), np.floor(x)
    wy, wx = np.stack(_bspline(y - y0), axis=1), np.stack(_bspline(x - x0), axis=1)
    cols = grid_cols + 2 * _PAD
    taps = np.arange(-1, 3)
    index = ((y0.astype(np.int64)[:, None] + taps) * cols)[:, :, None] + (
        x0.astype(np.int64)[:, None] + taps
    )[:, None, :]
    weight = (wy[:, :, None] * wx[:, None, :]).astype(np.float32)
    shape = (len(y), (grid_rows + 2 * _PAD) * cols)
    small = shape[1] < 2**31 and 16 * len(y) < 2**31
    kind = np.int32 if small else np.int64
    row_starts = np.arange(0, 16 * len(y) + 1, 16, dtype=kind)
    return sparse.csr_matrix((weight.ravel(), index.ravel().astype(kind), row_starts), shape=shape)


def clear_lookups() -> None:
    """Drop the cached interpolation matrices (the bench times a cold run with them gone)."""
    _lookup.cache_clear()


def phong_spectral(
    spectrum: np.ndarray, level: SpectralPlan, size: int, *, threads: int = 2
) -> npt.NDArray[np.float32]:
    """The Phong prefilter of the source at the cube texels of face n (module docstring).

    Parameters
    ----------
    spectrum
        :func:`source_spectrum` of the source, with at least ``level.frequencies`` terms.
    level
        :func:`plan` for the source's shape and N.
    size
        Face edge n.
    threads
        Threads for the level's product (more than 1: two pieces on a pool).

    Returns
    -------
    (6, n, n, 3) float32
        Equal to prefilter.brute_force.prefilter at cubemap.texel_directions(n) up to the
        terms left out and the interpolation (module docstring).
    """
    padded, before = _padded_spectrum(spectrum, [level])
    if threads > 1:
        with ThreadPoolExecutor(threads) as pool:
            return _level(padded, before, level, size, pool)
    return _level(padded, before, level, size, None)


def lobe_at(
    radiance: npt.ArrayLike,
    exponent: float,
    directions: npt.ArrayLike,
    *,
    eps: float = DEFAULT_EPS,
    min_rows: int = 16,
    oversample: float = 1.0,
    footprint: bool = False,
    threads: int = 2,
) -> npt.NDArray[np.float32]:
    """The Phong prefilter of a lat-long source at any directions (module docstring).

    E(r) = (N + 1)/2π Σ_l max(⟨r, l⟩, 0)^N L_l Δω_l, the brute force's sum over the source's
    texels, at each direction r; N = 1 gives the irradiance over π, ∫ L max(⟨n, l⟩, 0)/π.

    Parameters
    ----------
    radiance : (h, w, 3) array_like
        The lat-long source, linear radiance, each texel constant over its solid angle.
    exponent : float
        N > 0.
    directions : (..., 3) array_like
        Unit directions r.
    eps, min_rows, oversample, footprint, threads
        As :func:`plan` and :func:`phong_spectral`.

    Returns
    -------
    (..., 3) float32
        E at each direction: the brute force (with ``footprint``, the integral over each
        texel) up to the terms below ``eps`` of the lobe's peak and the cubic B-spline
        interpolation between the grid's exact sums.
    """
    image = np.asarray(radiance, dtype=np.float32)
    targets = np.asarray(directions, dtype=np.float64)
    level = plan(
        image.shape[0],
        image.shape[1],
        float(exponent),
        eps,
        min_rows=min_rows,
        oversample=oversample,
        footprint=footprint,
    )
    padded, before = _padded_spectrum(source_spectrum(image, level.frequencies), [level])
    with ThreadPoolExecutor(max(threads, 1)) as pool:
        spectrum = _grid_spectrum(padded, before, level, pool if threads > 1 else None)
    grid = _spline_grid(spectrum, level.grid_cols)
    uv = latlong.direction_to_uv(targets.reshape(-1, 3)).reshape(-1, 2)
    out = _basis(uv, level.grid_rows, level.grid_cols) @ grid.reshape(-1, 3)
    return np.asarray(out, dtype=np.float32).reshape(*targets.shape[:-1], 3)


def _level(padded, before, level: SpectralPlan, size: int, pool) -> npt.NDArray[np.float32]:
    """One level: the grid's spectrum, its spline coefficients, the basis at the texels."""
    grid = _spline_grid(_grid_spectrum(padded, before, level, pool), level.grid_cols)
    basis = _lookup(size, level.grid_rows, level.grid_cols)
    out = basis @ grid.reshape(-1, 3)
    return np.asarray(out, dtype=np.float32).reshape(6, size, size, 3)


def spectral_chain(
    radiance: npt.ArrayLike,
    size: int,
    levels: int,
    scale: float,
    bias: float,
    *,
    eps: float = DEFAULT_EPS,
    threads: int = 2,
) -> list[ChainLevel]:
    """Every level of the Phong cube chain (prefilter.chain) by :func:`phong_spectral`.

    Parameters
    ----------
    radiance
        (h, w, 3) lat-long radiance.
    size
        Face edge n of level 0, a power of two.
    levels
        L, 1 ≤ L ≤ log2(n) + 1.
    scale, bias
        The glossiness mapping's constants (prefilter.chain.gloss_exponents).
    eps
        :data:`DEFAULT_EPS`.
    threads
        The levels run on this many threads (level 0 on one, the rest on the others); each
        level's product on one.

    Returns
    -------
    list of ChainLevel
        Largest first, as prefilter.chain.prefiltered_chain returns them.
    """
    image = np.asarray(radiance, dtype=np.float32)
    h, w = image.shape[:2]
    exponents = gloss_exponents(levels, scale, bias)
    plans = [plan(h, w, float(exponent), eps) for exponent in exponents]
    faces = _chain_faces(image, size, plans, threads)
    return [ChainLevel(f, p.exponent, h) for f, p in zip(faces, plans, strict=True)]


def ggx_spectral_chain(
    radiance: npt.ArrayLike,
    size: int,
    levels: int,
    *,
    eps: float = DEFAULT_EPS,
    threads: int = 2,
) -> list[ChainLevel]:
    """The split-sum GGX cube chain: level k prefiltered with α_k (prefilter.roughness).

    Level 0 (α = 0, the mirror) is the environment resampled into the cube
    (core.resample.latlong_to_cube, as the GPU conversion does); every other level is
    the GGX lobe of prefilter.kernels.ggx (N = V = R) by :func:`plan` with ``kernel="ggx"``.

    Parameters
    ----------
    radiance
        (h, w, 3) lat-long radiance.
    size
        Face edge n of level 0, a power of two.
    levels
        K, 1 ≤ K ≤ log2(n) + 1; level k has faces of n >> k texels.
    eps, threads
        As :func:`spectral_chain`.

    Returns
    -------
    list of ChainLevel
        Largest first, ``kernel`` "ggx" and ``exponent`` α_k.
    """
    image = np.asarray(radiance, dtype=np.float32)
    h, w = image.shape[:2]
    alphas = roughness.level_alphas(levels)
    plans = [plan(h, w, alpha, eps, "ggx") for alpha in alphas[1:]]
    mirror = resample.latlong_to_cube(image, size).astype(np.float32)
    chain = [ChainLevel(mirror, 0.0, h, "ggx")]
    if plans:
        faces = _chain_faces(image, size, plans, threads, first_level=1)
        chain += [ChainLevel(f, p.exponent, h, "ggx") for f, p in zip(faces, plans, strict=True)]
    return chain


def _chain_faces(
    image: np.ndarray, size: int, plans: list[SpectralPlan], threads: int, first_level: int = 0
) -> list[npt.NDArray[np.float32]]:
    """The faces of every plan's level, plan j at level ``first_level`` + j (face n >> level)."""
    padded, before = _padded_spectrum(
        source_spectrum(image, max(p.frequencies for p in plans)), plans
    )
    edges = [max(1, size >> k) for k in range(first_level, first_level + len(plans))]
    if threads == 1:
        return [_level(padded, before, p, n, None) for p, n in zip(plans, edges, strict=True)]
    # Level 0 costs about as much as all the others (studies/prefilter-speed/README.md): it runs
    # on one thread, the rest on the others, each level's product single-threaded.
    with ThreadPoolExecutor(threads) as pool:
        futures = [
            pool.submit(_level, padded, before, p, n, None)
            for p, n in zip(plans, edges, strict=True)
        ]
        return [f.result() for f in futures]
