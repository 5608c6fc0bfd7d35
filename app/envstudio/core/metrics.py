"""Image error metrics over a mask: PSNR, SSIM (scikit-image), FLIP (flip-evaluator).

What the metrics look at
    PSNR, SSIM and FLIP all compare *display* images: the linear HDR frame
    through the display path (exposure, tone map, sRGB encoding, exactly the
    shader the screen uses, but read back as float so there is no 8-bit
    rounding), clipped to [0, 1]. One domain for all three keeps them
    consistent with each other and with what the viewer shows; SSIM and
    LDR-FLIP are defined on display-referred images, and in linear radiance a
    handful of pixels reflecting a light source (10³–10⁵ × the mean in the
    shipped maps) would decide the whole PSNR. The exposure and tone map are
    the ones the comparison ran with (``--param exposure=… tonemap=…``), so the
    same command can judge the shadows or the highlights. The linear view is
    kept in :func:`relative_error`, the heat map of the viewer's split screen.

Only the reflector's pixels count (the mask); elsewhere both images show the
same background and local objects.

PSNR
    10 log10(1 / MSE), MSE over the masked pixels and the three channels;
    +inf when the images agree exactly there.
SSIM
    :func:`skimage.metrics.structural_similarity` with the settings of Wang et
    al. (2004): Gaussian window σ = 1.5 (11 × 11), population covariances,
    data range 1, per channel. It runs on the mask's bounding box grown by the
    window radius (so pixels at the mask's edge see real neighbours, not
    reflected padding) and the SSIM map is averaged over the masked pixels.
FLIP
    LDR-FLIP (Andersson et al. 2020) of flip-evaluator on the sRGB display
    images at its default 67 pixels per degree, averaged over the masked
    pixels. LDR rather than HDR-FLIP: HDR-FLIP brackets exposures with its own
    tone mapper, which is not the one on the screen.
"""

from __future__ import annotations

from dataclasses import dataclass

import flip_evaluator
import numpy as np
import numpy.typing as npt
from skimage.metrics import structural_similarity

from envstudio.core.env_sampling import LUMINANCE

SSIM_SIGMA = 1.5
"""Standard deviation of SSIM's Gaussian window in pixels (Wang et al. 2004)."""
SSIM_WINDOW = 11
"""Width of that window: scikit-image truncates the Gaussian at 3.5 σ."""
MIN_SIZE = SSIM_WINDOW
"""Smallest image width and height the metrics accept."""
RELATIVE_FLOOR = 1e-3
"""Luminance below which :func:`relative_error` divides by this instead (as the viewer)."""


@dataclass(frozen=True)
class ImageMetrics:
    """The three metrics of one image against the reference, and the per-pixel FLIP error.

    Attributes
    ----------
    psnr_db : float
        Peak signal-to-noise ratio in dB (peak 1); +inf when identical on the mask.
    ssim : float
        Mean SSIM over the masked pixels, at most 1.
    flip : float
        Mean LDR-FLIP error over the masked pixels, in [0, 1].
    flip_map : (h, w) float32
        LDR-FLIP error of every pixel, in [0, 1].
    """

    psnr_db: float
    ssim: float
    flip: float
    flip_map: npt.NDArray[np.float32]


def compare_images(
    test: npt.ArrayLike, reference: npt.ArrayLike, mask: npt.ArrayLike
) -> ImageMetrics:
    """PSNR, SSIM and FLIP of ``test`` against ``reference`` over ``mask``.

    Parameters
    ----------
    test, reference
        (h, w, 3) float display images (sRGB-encoded, clipped to [0, 1] here),
        row 0 at the top; h, w ≥ :data:`MIN_SIZE`.
    mask
        (h, w) bool, the pixels that count; at least one True.

    Returns
    -------
    ImageMetrics
    """
    test, reference, mask = _checked(test, reference, mask)
    flip_map = _flip_map(test, reference)
    return ImageMetrics(
        psnr(test, reference, mask),
        ssim(test, reference, mask),
        float(flip_map[mask].mean()),
        flip_map,
    )


def psnr(test: npt.ArrayLike, reference: npt.ArrayLike, mask: npt.ArrayLike) -> float:
    """PSNR in dB with peak 1 over the masked pixels (shapes as :func:`compare_images`)."""
    test, reference, mask = _checked(test, reference, mask)
    mse = float(np.mean((test[mask] - reference[mask]) ** 2))
    return float("inf") if mse == 0.0 else float(-10.0 * np.log10(mse))


def flip(test: npt.ArrayLike, reference: npt.ArrayLike, mask: npt.ArrayLike) -> float:
    """Mean LDR-FLIP over the masked pixels (shapes as :func:`compare_images`), alone: the
    viewer's grid labels want it without SSIM."""
    test, reference, mask = _checked(test, reference, mask)
    return float(_flip_map(test, reference)[mask].mean())


def ssim(test: npt.ArrayLike, reference: npt.ArrayLike, mask: npt.ArrayLike) -> float:
    """Mean SSIM over the masked pixels (shapes as :func:`compare_images`; module docstring)."""
    test, reference, mask = _checked(test, reference, mask)
    rows, cols = _grown_box(mask, SSIM_WINDOW // 2)
    _, ssim_map = structural_similarity(
        test[rows, cols],
        reference[rows, cols],
        data_range=1.0,
        channel_axis=-1,
        gaussian_weights=True,
        sigma=SSIM_SIGMA,
        use_sample_covariance=False,
        full=True,
    )
    return float(ssim_map[mask[rows, cols]].mean())


def relative_error(
    test_hdr: npt.ArrayLike, reference_hdr: npt.ArrayLike
) -> npt.NDArray[np.float32]:
    """Per-pixel relative luminance error |Y_test − Y_ref| / max(Y_ref, 10⁻³) of linear images.

    The quantity of the viewer's heat map (shaders/frame/split.glsl).

    Parameters
    ----------
    test_hdr, reference_hdr
        (h, w, 3) float linear radiance.

    Returns
    -------
    (h, w) float32
        Unitless, ≥ 0.
    """
    y_test = np.asarray(test_hdr, dtype=np.float64) @ LUMINANCE
    y_ref = np.asarray(reference_hdr, dtype=np.float64) @ LUMINANCE
    if y_test.shape != y_ref.shape or y_test.ndim != 2:
        raise ValueError(f"expected two (h, w, 3) images, got {y_test.shape} and {y_ref.shape}")
    return (np.abs(y_test - y_ref) / np.maximum(y_ref, RELATIVE_FLOOR)).astype(np.float32)


def _flip_map(test: npt.NDArray[np.float32], reference: npt.NDArray[np.float32]):
    error, _, _ = flip_evaluator.evaluate(
        reference, test, "LDR", inputsRGB=True, applyMagma=False, computeMeanError=False
    )
    return np.asarray(error, dtype=np.float32).reshape(test.shape[:2])


def _grown_box(mask: npt.NDArray[np.bool_], margin: int) -> tuple[slice, slice]:
    """Row and column slices of the mask's bounding box grown by ``margin``, at least
    :data:`SSIM_WINDOW` wide, kept inside the image."""
    h, w = mask.shape
    ys, xs = np.nonzero(mask)

    def span(lo: int, hi: int, size: int) -> slice:
        lo, hi = max(lo - margin, 0), min(hi + 1 + margin, size)
        short = SSIM_WINDOW - (hi - lo)
        if short > 0:
            lo = max(min(lo - short // 2, size - SSIM_WINDOW), 0)
            hi = lo + SSIM_WINDOW
        return slice(lo, hi)

    return span(int(ys.min()), int(ys.max()), h), span(int(xs.min()), int(xs.max()), w)


def _checked(test, reference, mask):
    test = np.clip(np.asarray(test, dtype=np.float32), 0.0, 1.0)
    reference = np.clip(np.asarray(reference, dtype=np.float32), 0.0, 1.0)
    mask = np.asarray(mask, dtype=bool)
    if test.shape != reference.shape or test.ndim != 3 or test.shape[2] != 3:
        raise ValueError(
            f"expected two (h, w, 3) display images, got {test.shape} and {reference.shape}"
        )
    if mask.shape != test.shape[:2]:
        raise ValueError(f"mask is {mask.shape}, expected {test.shape[:2]}")
    if min(mask.shape) < MIN_SIZE:
        raise ValueError(
            f"images are {mask.shape[1]}x{mask.shape[0]}, at least {MIN_SIZE}x{MIN_SIZE}"
        )
    if not mask.any():
        raise ValueError("the mask is empty: no pixel to compare")
    return test, reference, mask
