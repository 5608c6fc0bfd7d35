"""What a pixel's sums of batch means say: the estimate, its standard error, the noise.

The sums are RGBA float arrays, (h, w, 4): ``total`` holds per pixel the sum of
its batch means (RGB, radiance) and its batch count (A); ``squares`` the sum of
the squared batch means (RGB).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from envstudio.core.env_sampling import LUMINANCE


def mean_of_batches(total: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
    """(h, w, 3) mean radiance over the batches (0 where a pixel has none)."""
    return total[..., :3] / np.maximum(total[..., 3:], 1.0)


def batch_variance(
    total: npt.NDArray[np.float32], squares: npt.NDArray[np.float32]
) -> npt.NDArray[np.float32]:
    """(h, w, 3) sample variance of each pixel's batch means (inf with fewer than two)."""
    k = total[..., 3:]
    safe = np.maximum(k, 2.0)
    mean = total[..., :3] / safe
    variance = np.maximum(squares[..., :3] / safe - mean**2, 0.0) * safe / (safe - 1.0)
    return np.where(k >= 2, variance, np.float32(np.inf))


def standard_error(
    total: npt.NDArray[np.float32], squares: npt.NDArray[np.float32]
) -> npt.NDArray[np.float32]:
    """(h, w, 3) standard error of :func:`mean_of_batches` from the spread of the batch means.

    With batches of different sizes the spread estimates their mean
    variance, and the error of their mean is still its square root over the
    batch count.
    """
    return np.sqrt(batch_variance(total, squares) / np.maximum(total[..., 3:], 1.0))


def noise(total: npt.NDArray[np.float32], squares: npt.NDArray[np.float32]) -> float:
    """:func:`median_relative_error` of the mean over the pixels with batches (unitless)."""
    return median_relative_error(
        mean_of_batches(total), standard_error(total, squares), total[..., 3] > 0
    )


def median_relative_error(
    estimate: npt.NDArray[np.float32],
    error: npt.NDArray[np.float32],
    mask: npt.NDArray[np.bool_],
) -> float:
    """Median over ``mask`` of the luminance error over the luminance of the estimate.

    Parameters
    ----------
    estimate, error : (h, w, 3) float
        Mean radiance and its standard error per channel (channel errors
        are added in the luminance: an upper bound).
    mask : (h, w) bool
        The pixels measured; those of zero luminance are left out.

    Returns
    -------
    float
        Unitless; inf when no pixel of ``mask`` is lit.
    """
    estimate_y = estimate[mask] @ LUMINANCE
    error_y = error[mask] @ LUMINANCE
    lit = estimate_y > 0
    if not lit.any():
        return float("inf")
    return float(np.median(error_y[lit] / estimate_y[lit]))
