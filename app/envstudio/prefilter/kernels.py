"""Radially symmetric prefilter kernels k(⟨r, l⟩) of seed 004 §4.

Each kernel is split as k(c) = scale · k̂(c), with k̂ the shape normalised to a
peak of 1. The brute force and the hierarchical prefilter sum k̂ and multiply by
``scale`` at the end; the hierarchical threshold (seed 004 §5.1, "difference in
BRDF values") is a difference of k̂, i.e. of the paper's Phong BRDF with k_s = 1.

- diffuse (seed 004 §4, Miller's map): k(c) = k_d/π · max(c, 0), c = ⟨n, l⟩; the
  1/π makes a constant environment L give k_d L.
- Phong (seed 004 §4, Heidrich's and Miller's map): k(c) = (N + 1)/2π · max(c, 0)^N,
  c = ⟨r_v, l⟩, normalised as seed 000 eq. 7 so a constant L gives L; the shape
  is floored at e^−80 ≈ 2·10⁻³⁵ (never subnormal in float32).
- GGX (split sum, Karis 2013): k(c) = D(h)/4 · max(c, 0) / W(α), c = ⟨r, l⟩, h the half
  vector of r and l (n·h = √((1 + c)/2)) with n = v = r: what method ``splitsum``
  prefilters per level (prefilter.chain_gpu.ggx_lobe_samples), normalised by
  core.ggx.reflected_lobe_integral so a constant L gives L.
- lobe (seed 004 §4, Kautz–McCool's 2D approximation): a tabulated radially
  symmetric p(c), linear between the rows of a two-column CSV (cosine, value),
  zero outside the tabulated cosines; not renormalised.

Evaluation works in place on float32 arrays of cosines, since it is the inner
loop of both prefilters (about 10⁹ values for the paper's 128×256 map).
"""

from __future__ import annotations

import csv
import functools
import math
import os
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from envstudio.core import ggx as ggx_model
from envstudio.errors import InputFileError, ParameterError

__all__ = ["KERNELS", "Kernel", "diffuse", "ggx", "lobe", "phong", "read_lobe_table"]

KERNELS = ("diffuse", "phong", "lobe")

# ln of the smallest Phong shape value computed, e^-80: normal in float32 (whose least is e^-87.3).
_LOG_FLOOR = -80.0
# The least normal float32: the cosine floor for exponents below 1, where e^(-80/N) underflows.
_SMALLEST_NORMAL = float(np.finfo(np.float32).tiny)
# Entries of the uniform look-up table a lobe is resampled to, over c ∈ [−1, 1].
_LUT_SIZE = 8192


@dataclass(frozen=True)
class Kernel:
    """k(c) = scale · k̂(c) with max k̂ = 1 (module docstring).

    Attributes
    ----------
    name
        "diffuse", "phong", "ggx" or "lobe".
    scale
        Peak value of k, in 1/sr.
    exponent
        Phong N (1 for diffuse, 0 for a lobe); GGX α for "ggx".
    lut
        Lobe only: (_LUT_SIZE + 1,) float32 samples of k̂ at c = −1 … 1.
    """

    name: str
    scale: float
    exponent: float = 1.0
    lut: np.ndarray | None = field(default=None, repr=False, compare=False)

    def shape_inplace(self, cos: np.ndarray) -> np.ndarray:
        """Overwrite an array of cosines with k̂(c) and return it.

        Parameters
        ----------
        cos
            (...) float32 cosines ⟨r, l⟩ in [−1, 1]; overwritten.

        Returns
        -------
        (...) float32
            The same array, now k̂(c) ∈ [0, 1].
        """
        if self.name == "diffuse":
            return np.maximum(cos, 0.0, out=cos)
        if self.name == "phong":
            # max(c, 0)^N as exp(N log c): NumPy's float32 exp and log are SIMD, pow is not.
            # c is floored where c^N = e^-80 (2e-35): below it float32 turns subnormal, and
            # arithmetic on subnormals is about a hundred times slower.
            np.maximum(cos, self.cosine_floor, out=cos)
            np.log(cos, out=cos)
            np.multiply(cos, np.float32(self.exponent), out=cos)
            return np.exp(cos, out=cos)
        if self.name == "ggx":
            # D(h)/D(1) · max(c, 0) with (n·h)² = (1 + c)/2: α⁴ c / (α² + (1 − α²)(1 − c)/2)²
            a2 = np.float32(self.exponent**2)
            c = np.maximum(cos, 0.0, out=cos)
            denominator = (np.float32(1.0) - c) * np.float32(0.5) * (np.float32(1.0) - a2) + a2
            return np.multiply(c, a2 * a2 / (denominator * denominator), out=cos)
        return _lookup(self.lut, cos)

    @property
    def cosine_floor(self) -> np.float32:
        """The least cosine the Phong shape is computed at: c^N = e^−80, a normal float32."""
        return np.float32(max(math.exp(_LOG_FLOOR / self.exponent), _SMALLEST_NORMAL))

    def spread(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """max k̂ − min k̂ over each cosine interval [lo, hi] (the hierarchical test).

        Parameters
        ----------
        lo, hi
            (...) float32 interval ends, lo ≤ hi, both overwritten.

        Returns
        -------
        (...) float32
            The spread; diffuse and Phong grow with c, so it is k̂(hi) − k̂(lo),
            a lobe reads its table's running extremes (:func:`_extremes`).
        """
        if self.lut is None:
            return np.subtract(self.shape_inplace(hi), self.shape_inplace(lo), out=hi)
        return _table_spread(self.lut, lo, hi)

    def derivative_bound(self, lo: np.ndarray, hi: np.ndarray, order: int) -> np.ndarray:
        """An upper bound of |k̂⁽ᵐ⁾(c)|, m = ``order`` ≥ 1, over each interval [lo, hi].

        For max(c, 0)^N, k̂⁽ᵐ⁾ = N (N − 1) … (N − m + 1) c^(N−m) where c > 0 and 0 where
        c < 0: with N ≥ m its magnitude grows with c, so the bound is its value at
        max(hi, 0); with N < m it is unbounded at c = 0 (or jumps there): its value at
        lo if lo > 0, 0 if hi ≤ 0, inf otherwise. A tabulated lobe is piecewise
        linear with kinks: inf (the hierarchical method then uses only the spread).

        Parameters
        ----------
        lo, hi
            (...) float32 interval ends, lo ≤ hi (not overwritten).
        order
            m.

        Returns
        -------
        (...) float32 or float64
        """
        return self._power_bound(lo, hi, order)

    def _power_bound(self, lo: np.ndarray, hi: np.ndarray, order: int) -> np.ndarray:
        """max |d^order/dc^order max(c, 0)^N| over [lo, hi] (:meth:`derivative_bound`)."""
        if self.lut is not None or self.name == "ggx":
            return np.full(np.shape(hi), np.inf, np.float32)
        n = self.exponent
        factor = math.prod(n - k for k in range(order))
        power = np.float32(n - order)
        if n >= order:
            return np.float32(factor) * np.maximum(hi, 0.0) ** power
        inside = abs(factor) * np.maximum(lo, 1e-30).astype(np.float64) ** power
        bound = np.where(lo > 0.0, inside, np.inf)
        return np.where(hi <= 0.0, np.float32(0.0), bound).astype(np.float32)

    def shape(self, cos: npt.ArrayLike) -> np.ndarray:
        """k̂(c) of a copy of ``cos``: (...) float → (...) float32."""
        return self.shape_inplace(np.array(cos, dtype=np.float32))

    def __call__(self, cos: npt.ArrayLike) -> np.ndarray:
        """k(c) = scale · k̂(c), in 1/sr: (...) float → (...) float64."""
        return self.scale * self.shape(cos).astype(np.float64)


def diffuse(kd: float = 1.0) -> Kernel:
    """k_d/π · max(⟨n, l⟩, 0) (seed 004 §4, L_diffuse, with the BRDF k_d/π).

    Raises
    ------
    ParameterError
        Unless 0 < k_d ≤ 1.
    """
    if not 0.0 < kd <= 1.0:
        raise ParameterError(f"--kd {kd}: expected a diffuse albedo in (0, 1]")
    return Kernel("diffuse", kd / math.pi)


def phong(exponent: float) -> Kernel:
    """(N + 1)/2π · max(⟨r, l⟩, 0)^N (seed 004 §4, L_phong; seed 000 eq. 7's normalisation).

    Raises
    ------
    ParameterError
        Unless 0 < N ≤ 100000.
    """
    if not 0.0 < exponent <= 1e5:
        raise ParameterError(f"--exponent {exponent:g}: expected a Phong exponent in (0, 100000]")
    return Kernel("phong", (exponent + 1.0) / (2.0 * math.pi), float(exponent))


def ggx(alpha: float) -> Kernel:
    """The split-sum GGX lobe about r, n = v = r (module docstring; Karis 2013).

    Raises
    ------
    ParameterError
        Unless 0 < α ≤ 1.
    """
    if not 0.0 < alpha <= 1.0:
        raise ParameterError(f"roughness={alpha:g}: expected a GGX alpha in (0, 1]")
    peak = float(ggx_model.distribution(1.0, alpha)) / 4.0
    return Kernel("ggx", peak / ggx_model.reflected_lobe_integral(alpha), float(alpha))


def lobe(cosines: npt.ArrayLike, values: npt.ArrayLike, source: str = "lobe table") -> Kernel:
    """A tabulated radially symmetric lobe p(⟨r, l⟩) (seed 004 §4, Kautz and McCool's p).

    Parameters
    ----------
    cosines
        (m,) strictly increasing cosines in [−1, 1], m ≥ 2.
    values
        (m,) lobe values p ≥ 0 in 1/sr, not all zero.
    source
        Name for error messages (the CSV file).

    Raises
    ------
    ParameterError
        If the table has fewer than two rows, its cosines are not strictly
        increasing within [−1, 1], or its values are negative, not finite or all zero.
    """
    c = np.asarray(cosines, dtype=np.float64)
    p = np.asarray(values, dtype=np.float64)
    if c.ndim != 1 or c.shape != p.shape or len(c) < 2:
        raise ParameterError(f"--lobe {source}: expected at least 2 rows, got {c.size}")
    if not np.all(np.isfinite(c)) or c[0] < -1.0 or c[-1] > 1.0 or np.any(np.diff(c) <= 0):
        raise ParameterError(
            f"--lobe {source}: the first column (cosines) must increase strictly within [-1, 1]"
        )
    if not np.all(np.isfinite(p)) or np.any(p < 0) or not np.any(p > 0):
        raise ParameterError(
            f"--lobe {source}: the second column (lobe values) must be finite, >= 0, not all 0"
        )
    peak = float(p.max())
    grid = np.linspace(-1.0, 1.0, _LUT_SIZE + 1)
    shape = np.interp(grid, c, p / peak, left=0.0, right=0.0)
    return Kernel("lobe", peak, 0.0, shape.astype(np.float32))


def read_lobe_table(path: str | os.PathLike) -> Kernel:
    """Read a two-column CSV (cosine, value), an optional header row, into a lobe kernel.

    Raises
    ------
    InputFileError
        If the file is missing or a row is not two numbers.
    ParameterError
        As :func:`lobe`.
    """
    rows = []
    try:
        with open(path, newline="", encoding="utf-8") as f:
            for k, row in enumerate(csv.reader(f)):
                if not row or all(not cell.strip() for cell in row):
                    continue
                try:
                    if len(row) != 2:
                        raise ValueError
                    rows.append((float(row[0]), float(row[1])))
                except ValueError:
                    if k == 0 and not rows:
                        continue  # a header
                    raise InputFileError(
                        f"--lobe {path}: line {k + 1} is not two numbers (cosine, value)"
                    ) from None
    except OSError as exc:
        raise InputFileError(f"--lobe {path}: cannot read ({exc.strerror})") from None
    table = np.array(rows, dtype=np.float64).reshape(-1, 2)
    return lobe(table[:, 0], table[:, 1], str(path))


def _table_spread(lut: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """max − min of a uniform table over [−1, 1] on each interval [lo, hi] (in place).

    Conservative: the table's entries from the one at or below lo to the one at
    or above hi, through a sparse table of maxima and minima over 2^k entries.
    """
    high, low = _extremes(lut.tobytes())
    i = np.clip(np.floor((lo + 1.0) * (_LUT_SIZE / 2)).astype(np.int32), 0, _LUT_SIZE)
    j = np.clip(np.ceil((hi + 1.0) * (_LUT_SIZE / 2)).astype(np.int32), 0, _LUT_SIZE)
    k = np.floor(np.log2(np.maximum(j - i + 1, 1))).astype(np.int32)
    end = j - (1 << k) + 1
    top = np.maximum(high[k, i], high[k, end])
    bottom = np.minimum(low[k, i], low[k, end])
    return np.subtract(top, bottom, out=hi)


@functools.cache
def _extremes(table: bytes) -> tuple[np.ndarray, np.ndarray]:
    """Sparse tables: [k, i] = max (min) of entries i … i + 2^k − 1 (clamped at the end)."""
    lut = np.frombuffer(table, np.float32)
    levels = int(np.log2(len(lut))) + 1
    high, low = np.empty((levels, len(lut)), np.float32), np.empty((levels, len(lut)), np.float32)
    high[0] = low[0] = lut
    for k in range(1, levels):
        step = 1 << (k - 1)
        shifted = np.minimum(np.arange(len(lut)) + step, len(lut) - 1)
        high[k] = np.maximum(high[k - 1], high[k - 1][shifted])
        low[k] = np.minimum(low[k - 1], low[k - 1][shifted])
    return high, low


def _lookup(lut: np.ndarray, cos: np.ndarray) -> np.ndarray:
    """Linear interpolation of a uniform table over [−1, 1], in place on float32 cosines."""
    x = np.clip(cos, -1.0, 1.0, out=cos)
    x += 1.0
    x *= np.float32(_LUT_SIZE / 2)
    i = np.minimum(x.astype(np.int32), _LUT_SIZE - 1)
    x -= i
    lo = lut[i]
    return np.add(lo, x * (lut[i + 1] - lo), out=cos)
