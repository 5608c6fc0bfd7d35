"""Schlick's Fresnel approximation (seed 000 section 5.2, Schlick 1994)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt


def schlick(f0: float | npt.ArrayLike, cos_theta: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Fresnel reflectance F = f_λ + (1 − f_λ)(1 − cos θ)^5.

    Parameters
    ----------
    f0
        f_λ, reflectance at normal incidence, in [0, 1].
    cos_theta
        Cosine between the view (or reflection) direction and the normal; clamped to [0, 1].
    """
    c = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)
    return np.asarray(f0, dtype=np.float64) + (1.0 - np.asarray(f0)) * (1.0 - c) ** 5
