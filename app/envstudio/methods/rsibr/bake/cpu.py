"""CPU (NumPy) bake of radiance sphere maps: the fallback of bake.rsibr.gpu.

Quadrature over the texels of a lat-long copy of the environment with their
exact solid angles: for each lobe (bake.rsibr.brdfs) a map texel is

    Σ_l s(l) a(l) L(l) dω_l / Σ_l s(l) dω_l,

normalized by the quadrature of the lobe's own unit integral, so a constant
environment gives exactly the constant (seed 002 §2's integral of a kernel of
integral 1) and a lobe narrower than the working resolution keeps its energy.
The environment is box-filtered (solid-angle weighted) to the working height
:func:`working_height`, about 8 texels across a Phong lobe's width 1/sqrt(N).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from envstudio.core import latlong
from envstudio.core.fresnel import schlick
from envstudio.core.resample import sample_latlong
from envstudio.methods.rsibr.bake.brdfs import brdf
from envstudio.methods.rsibr.warp import g_mirror, g_normal

__all__ = ["bake_view_cpu", "downsample", "texel_uv", "working_height"]

_CHUNK = 1024  # map texels per matrix product


def texel_uv(size: int) -> npt.NDArray[np.float64]:
    """(n, n, 2) float64 sphere-map coordinates of the texel centres (row ↔ t)."""
    st = (np.arange(size) + 0.5) / size
    ss, tt = np.meshgrid(st, st)
    return np.stack([ss, tt], axis=-1)


def working_height(name: str, values: dict[str, float], source_height: int) -> int:
    """Lat-long height the CPU integrates over (a power of two, at most the source's)."""
    exponent = {"phong": "phong_exponent", "carpaint": "base_exponent"}.get(name)
    width = 8.0 * np.sqrt(values[exponent] + 1.0) if exponent else 16.0
    height = 2 ** int(np.ceil(np.log2(max(width, 16.0))))
    return int(min(source_height, height))


def downsample(image: npt.ArrayLike, height: int) -> npt.NDArray[np.float64]:
    """Solid-angle-weighted box filter of a lat-long map to ``height`` rows.

    Parameters
    ----------
    image : (h, 2h, 3) float
        Lat-long radiance; h must be a multiple of ``height``.
    height
        Target rows.

    Returns
    -------
    (height, 2 height, 3) float64
    """
    image = np.asarray(image, dtype=np.float64)
    h = image.shape[0]
    if h % height:
        raise ValueError(f"lat-long height {h} is not a multiple of {height}")
    k = h // height
    weight = latlong.texel_solid_angles(h)[:, :1]
    blocks = (image * weight[..., None]).reshape(height, k, 2 * height, k, 3).sum(axis=(1, 3))
    return blocks / weight.reshape(height, k).sum(axis=1)[:, None, None] / k


def bake_view_cpu(
    environment: npt.ArrayLike,
    name: str,
    values: dict[str, float],
    frame: npt.ArrayLike,
    size: int,
    progress: Callable[[int], None] | None = None,
) -> npt.NDArray[np.float32]:
    """One radiance sphere map L_r,j (seed 002 §2, §3.1) on the CPU.

    Parameters
    ----------
    environment : (h, 2h, 3) float
        Lat-long radiance at infinity (linear RGB), row 0 = +Y.
    name
        BRDF name (bake.rsibr.brdfs).
    values
        All its parameters (:meth:`Brdf.values`).
    frame : (3, 3) float
        The view's camera frame T_j (methods.rsibr.warp.view_frame).
    size
        Map edge n in texels.
    progress
        Called with the number of texels finished since the last call.

    Returns
    -------
    (n, n, 3) float32
        Linear radiance, core.spheremap layout; texels outside the disc hold the rim's value.
    """
    spec = brdf(name)
    env = np.asarray(environment, dtype=np.float64)
    height = working_height(name, values, env.shape[0])
    while env.shape[0] % height:
        height //= 2
    small = downsample(env, height)
    dirs = latlong.texel_directions(height).reshape(-1, 3)
    domega = latlong.texel_solid_angles(height).reshape(-1)
    radiance = small.reshape(-1, 3)
    t = np.asarray(frame, dtype=np.float64)
    uv = texel_uv(size).reshape(-1, 2)
    normals = g_normal(uv) @ t.T
    mirrors = g_mirror(uv) @ t.T
    view = t[:, 2]
    out = np.empty((len(uv), 3))
    for lo in range(0, len(uv), _CHUNK):
        n, r = normals[lo : lo + _CHUNK], mirrors[lo : lo + _CHUNK]
        if spec.name == "phong":
            out[lo : lo + _CHUNK] = _lobe(
                r @ dirs.T, values["phong_exponent"], 1.0, radiance, domega
            )
        elif spec.name == "lambertian":
            out[lo : lo + _CHUNK] = _lobe(n @ dirs.T, 1.0, 1.0, radiance, domega, cosine=True)
        else:
            out[lo : lo + _CHUNK] = _carpaint(n, r, view, values, env, dirs, radiance, domega)
        if progress is not None:
            progress(len(n))
    return out.reshape(size, size, 3).astype(np.float32)


def _lobe(
    cosines: np.ndarray,
    exponent: float,
    attenuation: np.ndarray | float,
    radiance: np.ndarray,
    domega: np.ndarray,
    cosine: bool = False,
) -> np.ndarray:
    """(B, 3) Σ s a L dω / Σ s dω for s ∝ max(cos, 0)^exponent (cosine: the clamped cosine)."""
    s = np.maximum(cosines, 0.0)
    if not cosine:
        s = s**exponent
    s = s * domega
    total = s.sum(axis=1, keepdims=True)
    weighted = (s * attenuation) @ radiance
    return np.divide(weighted, total, out=np.zeros_like(weighted), where=total > 0)


def _carpaint(
    n: np.ndarray,
    r: np.ndarray,
    view: np.ndarray,
    values: dict[str, float],
    env: np.ndarray,
    dirs: np.ndarray,
    radiance: np.ndarray,
    domega: np.ndarray,
) -> np.ndarray:
    """(B, 3) the car paint of the module docstring of bake.rsibr.brdfs."""
    f0 = values["coat_f0"]
    colour = np.array([values["paint_red"], values["paint_green"], values["paint_blue"]])
    n_dot_l = n @ dirs.T
    through = np.where(n_dot_l > 0.0, 1.0 - schlick(f0, n_dot_l), 0.0)
    glossy = _lobe(r @ dirs.T, values["base_exponent"], through, radiance, domega)
    diffuse = _lobe(n_dot_l, 1.0, through, radiance, domega, cosine=True)
    base = colour * (values["metallic"] * glossy + (1.0 - values["metallic"]) * diffuse)
    coat = schlick(f0, n @ view)[:, None]
    return coat * sample_latlong(env, r) + (1.0 - coat) * base
