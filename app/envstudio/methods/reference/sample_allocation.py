"""Per-pixel sample allocation of the adaptive reference (methods/reference/method.py).

Pixel i draws m_i × ``samples`` estimates per batch; the multipliers are set
again at every doubling, in proportion to each pixel's standard deviation
(Neyman allocation: n_i ∝ sigma_i minimises the summed variance for the
work), as powers of two between 1 and :data:`MAX_MULTIPLIER`, relative to the
:data:`REFERENCE_PERCENTILE`-th percentile of all pixels' deviations. The
plain rate is the floor, so no pixel gets fewer samples than without it.

Every batch mean keeps weight 1 in the estimate, whatever its size. Weighting
batches by their sizes would make a pixel's weights depend on its own early
samples, which decided its later multipliers. A pixel that had by chance
missed a small bright source would then keep its low early batches at full
weight, while one that had hit it would dilute them: the mean is biased low.
(The first version did that and measured 0.82 of a small patch's analytic
lobe, but with 1024 samples per pixel and batch in one draw, where llvmpipe's
loop limit, :data:`SOFTWARE_SAMPLES_PER_BATCH`, alone costs 0.905.) With equal
weights each batch mean is unbiased given its size, and so is their average.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

MAX_MULTIPLIER = 4
REFERENCE_PERCENTILE = 80.0
#: llvmpipe ends every loop of a shader invocation once the invocation has run
#: 65 535 loop iterations in all (measured: a 70 × 1000 nested loop counts to
#: 65 405), silently: the estimate then misses terms and is biased (0.905 of the
#: analytic lobe at 1024 samples per pixel and batch). A traced sample runs a
#: few hundred iterations (the cap's rows, the CDF searches, the Sobol bits, the
#: BVH walk), so on software renderers a pixel draws at most this many per draw,
#: and a larger batch is drawn in chunks (methods/reference/estimator.py).
SOFTWARE_SAMPLES_PER_BATCH = 32


@dataclass
class SampleAllocation:
    """Where every pixel's sampling stands when its multipliers were last set.

    Arrays are (h, w), row 0 at the top.

    Attributes
    ----------
    units : float32
        Samples drawn before batch ``at``, in units of ``samples`` (sum of m_b):
        where the pixel's sample sequence continues.
    inverse : float64
        Sum of 1 / m_b over the same batches: the batch means' variances are
        sigma² / (``samples`` m_b), so their mean is sigma² inverse / batches.
    multipliers : float32
        m for the batches from ``at`` on.
    covered : bool
        Pixels on the reflectors (all True before the first allocation).
    at : int
        Batch count when the multipliers were set.
    """

    units: npt.NDArray[np.float32]
    inverse: npt.NDArray[np.float64]
    multipliers: npt.NDArray[np.float32]
    covered: npt.NDArray[np.bool_]
    at: int = 0

    @classmethod
    def plain(cls, shape: tuple[int, int], batches: int = 0) -> SampleAllocation:
        """Every pixel at m = 1 from the start (``batches`` already drawn at that rate)."""
        return cls(
            np.full(shape, batches, np.float32),
            np.full(shape, float(batches)),
            np.ones(shape, np.float32),
            np.ones(shape, bool),
            batches,
        )

    def at_batch(self, batches: int) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float64]]:
        """``units`` and ``inverse`` after ``batches`` batches."""
        since = batches - self.at
        return self.units + since * self.multipliers, self.inverse + since / self.multipliers

    def samples_per_pixel(self, batches: int, samples: int) -> int:
        """Mean estimates per covered pixel after ``batches`` batches of ``samples`` × m."""
        units, _ = self.at_batch(batches)
        covered = units[self.covered]
        return round(float(covered.mean()) * samples) if covered.size else batches * samples

    def reallocate(
        self,
        batches: int,
        batch_variance: npt.NDArray[np.float64],
        covered: npt.NDArray[np.bool_],
    ) -> SampleAllocation:
        """The allocation from batch ``batches`` on.

        Parameters
        ----------
        batches
            Batches drawn so far (all at the current multipliers since ``at``).
        batch_variance
            (h, w) sample variance of the pixels' batch means, summed over RGB
            (0 where unknown).
        covered
            (h, w) pixels on the reflectors.
        """
        units, inverse = self.at_batch(batches)
        sigma = np.zeros(batch_variance.shape)  # standard deviation of one plain batch
        known = covered & (inverse > 0)
        sigma[known] = np.sqrt(batch_variance[known] * batches / inverse[known])
        multipliers = neyman_multipliers(sigma, covered)
        return SampleAllocation(units, inverse, multipliers, covered, batches)

    def as_arrays(self) -> dict[str, npt.NDArray]:
        """The fields as arrays, for saving (:meth:`from_arrays` reads them back)."""
        return {
            "allocation_units": self.units,
            "allocation_inverse": self.inverse,
            "allocation_multipliers": self.multipliers,
            "allocation_covered": self.covered,
            "allocated_at": np.int64(self.at),
        }

    @classmethod
    def from_arrays(cls, state: dict[str, npt.NDArray], shape: tuple[int, int], batches: int):
        """The saved allocation, or plain sampling up to ``batches`` when ``state`` has none."""
        if "allocation_units" not in state or state["allocation_units"].shape != shape:
            return cls.plain(shape, batches)
        return cls(
            state["allocation_units"].astype(np.float32),
            state["allocation_inverse"].astype(np.float64),
            state["allocation_multipliers"].astype(np.float32),
            state["allocation_covered"].astype(bool),
            int(state["allocated_at"]),
        )


def neyman_multipliers(
    sigma: npt.NDArray[np.float64],
    covered: npt.NDArray[np.bool_],
) -> npt.NDArray[np.float32]:
    """(h, w) powers of two in 1 … :data:`MAX_MULTIPLIER` nearest to sigma / sigma_ref.

    sigma_ref is the :data:`REFERENCE_PERCENTILE`-th percentile of ``sigma``
    over the covered pixels; pixels off the reflectors, or all of them when no
    deviation is known yet, get 1.
    """
    multipliers = np.ones(sigma.shape, np.float32)
    positive = covered & (sigma > 0)
    if not positive.any():
        return multipliers
    reference = np.percentile(sigma[covered], REFERENCE_PERCENTILE)
    if reference <= 0:
        reference = sigma[positive].min()
    exponent = np.round(np.log2(sigma[positive] / reference))
    multipliers[positive] = np.clip(np.exp2(exponent), 1, MAX_MULTIPLIER)
    return multipliers
