"""The exact reference of the untraced environment-map model: no Monte Carlo, no noise.

Without tracing, the reference's answer at a footprint sample is a deterministic integral of
the environment over a lobe. For seed 000 eq. 8's model (the reference's ``model=phong``,
shaders/reference/material.glsl), at a surface point with shading normal n seen from v,

    L_o = (1 − F) k_d ∫ L(l) max(⟨n, l⟩, 0)/π dl + F (N + 1)/2π ∫ L(l) max(⟨r, l⟩, 0)^N dl,

F = Schlick(f_λ, ⟨n, v⟩) per channel, r = reflect(−v, n), both integrals over the whole
sphere of the environment as the reference sees it (each lat-long texel constant over its
solid angle): the diffuse term depends on n alone, the glossy one on r alone. Both are the
brute force's sums with each texel's lobe integrated over the texel (the map as a function
constant over each texel, which the Monte Carlo reference converges to however narrow the
lobe), evaluated at any direction by prefilter.spectral.lobe_at (N = 1 is the irradiance
over π). The samples are the ones compare renders every method at: ``ssaa`` ×
``ssaa`` per pixel, rasterised (engine FrameRenderer.reflector_surface, the reference's
two-sided rule), box-filtered over the covered ones (compare.footprint_filter). A sample
whose shading normal faces away from the viewer reflects nothing, as in the reference.

What it leaves out is stated and checked: the spectral sums drop the lobe below
``DEFAULT_EPS`` of its peak and interpolate between exact grid sums (cubic B-spline);
:func:`checked_error` holds the result against the plain brute-force sum (every texel, cut
into sub-texels finer than the lobe) at a fixed set of the samples and reports the median
and largest relative difference.

The ``microfacet`` (GGX) and ``banks`` models share the diffuse term; their glossy lobes
depend on (n, v) or (v, t) together, so no prefiltered map holds them: measure/exact_lobes.py
integrates them per sample on the GPU (Banks at the tangents of
engine FrameRenderer.reflector_tangents), and :func:`checked_error` holds them against the
same kind of brute-force sum. A plugin's own model has no exact evaluation:
:data:`EXACT_MODELS` lists those that have.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from envstudio.core import ggx, latlong
from envstudio.measure.exact_lobes import (
    LobeEvaluator,
    LobeModel,
    banks_lobe,
    check_size,
    microfacet_lobe,
)
from envstudio.prefilter import spectral

#: The reflectance models with an exact untraced evaluation here.
EXACT_MODELS = ("phong", "microfacet", "banks")
#: The models whose glossy lobe the GPU integrates (exact_lobes.py).
LOBE_MODELS = ("microfacet", "banks")
#: The reference's values a Banks lobe reads (shading/materials.py).
BANKS_VALUES = ("sharpness", "normalize", "self_shadowing", "tangent_field", "tangent_axis")
#: Rows of the spectral grid at least (N = 1's kink at the horizon wants a finer grid than
#: its width asks for; from 128 the diffuse sum is within 1e-4 (studio) and 3.3e-4 (sunrise)
#: of the brute force at every direction tried, as at 256).
GRID_ROWS = 128
#: Footprint samples held against the brute force by :func:`checked_error`.
CHECKED_SAMPLES = 64


def schlick(fresnel: npt.ArrayLike, cos_theta: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Schlick's F per channel (seed 000 §5.2): (..., 3) for (3,) f_λ and (...,) cosines."""
    m = 1.0 - np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)
    f0 = np.asarray(fresnel, dtype=np.float64)
    return f0 + (1.0 - f0) * (m**5)[..., None]


def eq8_terms(
    normals: npt.ArrayLike,
    views: npt.ArrayLike,
    fresnel: npt.ArrayLike,
    kd: npt.ArrayLike,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The frame of each sample: (facing, r, diffuse weight (1 − F) k_d, glossy weight F).

    Parameters
    ----------
    normals, views : (s, 3) array_like
        Unit shading normals (turned to the seen side of the face) and directions to the
        camera.
    fresnel, kd : (3,) array_like or float
        f_λ and k_d, linear RGB (a number: grey).

    Returns
    -------
    facing : (s,) bool
        ⟨n, v⟩ > 0: the sample reflects something.
    reflections : (s, 3) float64
        r = 2 ⟨n, v⟩ n − v.
    diffuse, glossy : (s, 3) float64
        (1 − F) k_d and F, zero where not facing.
    """
    n = np.asarray(normals, dtype=np.float64)
    v = np.asarray(views, dtype=np.float64)
    cos = np.einsum("sk,sk->s", n, v)
    facing = cos > 0.0
    glossy = schlick(np.broadcast_to(fresnel, 3), cos) * facing[:, None]
    diffuse = (1.0 - glossy) * np.broadcast_to(np.asarray(kd, np.float64), 3) * facing[:, None]
    return facing, 2.0 * cos[:, None] * n - v, diffuse, glossy


def eq8_radiance(
    radiance: npt.ArrayLike,
    normals: npt.ArrayLike,
    views: npt.ArrayLike,
    fresnel: npt.ArrayLike,
    kd: npt.ArrayLike,
    exponent: float,
) -> npt.NDArray[np.float32]:
    """Exitant radiance of the untraced ``model=phong`` at each sample (module docstring).

    Parameters
    ----------
    radiance : (h, w, 3) array_like
        The lat-long environment, linear radiance.
    normals, views : (s, 3) array_like
        As :func:`eq8_terms`.
    fresnel, kd : (3,) array_like or float
        f_λ and k_d.
    exponent : float
        The Phong exponent N.

    Returns
    -------
    (s, 3) float32
        Linear radiance.
    """
    _, reflections, diffuse, glossy = eq8_terms(normals, views, fresnel, kd)
    out = diffuse_radiance(radiance, normals, diffuse)
    if glossy.any():
        out += glossy * spectral.lobe_at(
            radiance, exponent, reflections, min_rows=GRID_ROWS, footprint=True
        )
    return out.astype(np.float32)


def diffuse_radiance(
    radiance: npt.ArrayLike, normals: npt.ArrayLike, weights: np.ndarray
) -> npt.NDArray[np.float64]:
    """(1 − F) k_d ∫ L(l) max(⟨n, l⟩, 0)/π dl for (s, 3) ``weights`` (1 − F) k_d, the same in
    every model (seed 000 eq. 3–4; material.glsl); (s, 3) float64, zero where the weights are."""
    out = np.zeros(weights.shape)
    if weights.any():  # k_d = 0 (a mirror-like material) skips the diffuse sums
        out += weights * spectral.lobe_at(
            radiance, 1.0, normals, min_rows=GRID_ROWS, footprint=True
        )
    return out


def exact_inputs(values: dict[str, object]) -> dict[str, object]:
    """The reference's values the exact evaluation of its model reads (:func:`exact_radiance`):
    f_λ, k_d and N, or for Banks its lobe's values instead of N."""
    model = str(values.get("model", "phong"))
    read = ("fresnel", "kd", *(BANKS_VALUES if model == "banks" else ("phong_exponent",)))
    return {"model": model} | {name: values[name] for name in read}


def lobe_model(values: dict[str, object]) -> LobeModel:
    """The glossy model of the reference's ``values`` (a model in :data:`LOBE_MODELS`)."""
    fresnel = tuple(float(c) for c in np.broadcast_to(values["fresnel"], 3))
    if values["model"] == "banks":
        return LobeModel(
            "banks",
            fresnel,
            sharpness=float(values["sharpness"]),
            normalize=bool(values["normalize"]),
            self_shadowing=bool(values["self_shadowing"]),
        )
    alpha = ggx.alpha_for_exponent(float(values["phong_exponent"]))
    return LobeModel(str(values["model"]), fresnel, alpha=alpha)


def exact_radiance(
    radiance: npt.ArrayLike,
    normals: npt.ArrayLike,
    views: npt.ArrayLike,
    values: dict[str, object],
    lobes: LobeEvaluator | None = None,
    tangents: npt.ArrayLike | None = None,
) -> npt.NDArray[np.float32]:
    """Exitant radiance of the reference's untraced model at each sample, exactly.

    Parameters
    ----------
    radiance : (h, w, 3) array_like
        The lat-long environment, linear radiance.
    normals, views : (s, 3) array_like
        As :func:`eq8_terms`.
    values : dict
        The reference's values: ``model`` (one of :data:`EXACT_MODELS`; phong when absent),
        ``fresnel``, ``kd``, ``phong_exponent``.
    lobes : LobeEvaluator or None
        The GPU integration of a model in :data:`LOBE_MODELS` (needed for those).
    tangents : (s, 3) array_like or None
        model=banks: unit tangents orthogonal to the normals (engine
        FrameRenderer.reflector_tangents).

    Returns
    -------
    (s, 3) float32
        Linear radiance.

    Raises
    ------
    ParameterError
        A map too large for the tables, naming the ``--max-env-width`` that fits
        (exact_lobes.check_size).
    """
    check_size(*np.shape(radiance)[:2])
    model = str(values.get("model", "phong"))
    fresnel = np.asarray(values["fresnel"], dtype=np.float64)
    kd = np.asarray(values["kd"], dtype=np.float64)
    if model == "phong":
        return eq8_radiance(radiance, normals, views, fresnel, kd, float(values["phong_exponent"]))
    if model not in LOBE_MODELS or lobes is None:
        raise ValueError(f"model={model}: no exact evaluation here (expected {EXACT_MODELS})")
    facing, _, diffuse, _ = eq8_terms(normals, views, fresnel, kd)
    out = diffuse_radiance(radiance, normals, diffuse)
    n, v = np.asarray(normals)[facing], np.asarray(views)[facing]
    t = None if tangents is None else np.asarray(tangents)[facing]
    out[facing] += lobes.glossy(radiance, lobe_model(values), n, v, t)
    return out.astype(np.float32)


def texel_split(height: int, exponent: float) -> int:
    """Sub-texels per texel edge for :func:`brute_force_radiance`: each at most half the
    lobe's width (about N^−½), where three Gauss points an axis integrate it closely."""
    return int(min(16, max(1, math.ceil(2.0 * (math.pi / height) * math.sqrt(exponent)))))


@functools.lru_cache(maxsize=1)
def gauss_texels(height: int, width: int, split: int) -> tuple[np.ndarray, np.ndarray]:
    """Quadrature points of the lat-long sphere that integrate a function over every texel:
    each texel cut into ``split`` × ``split`` parts of 3 × 3 Gauss–Legendre points. The last
    set is kept (read-only): every check of a frame and of the next reads the same points.

    Returns
    -------
    directions : (3 split h · 3 split w, 3) float64
        Unit directions, rows (θ) outermost, in the lat-long convention (core.latlong).
    weights : (3 split h · 3 split w,) float64
        Solid angle of each point, sr; they sum to 4π.
    """
    nodes = np.array([-math.sqrt(0.6), 0.0, math.sqrt(0.6)])
    gauss = np.array([5.0, 8.0, 5.0]) / 9.0
    theta_half = 0.5 * math.pi / (height * split)
    theta = (np.arange(height * split) + 0.5)[:, None] * 2.0 * theta_half + nodes * theta_half
    theta = theta.ravel()
    theta_w = np.tile(gauss * theta_half, height * split) * np.sin(theta)
    u_half = 0.5 / (width * split)
    u = ((np.arange(width * split) + 0.5)[:, None] * 2.0 * u_half + nodes * u_half).ravel()
    phi_w = np.tile(gauss * u_half, width * split) * 2.0 * math.pi
    uv = np.stack(np.broadcast_arrays(u[None, :], (theta / math.pi)[:, None]), axis=-1)
    directions = latlong.uv_to_direction(uv.reshape(-1, 2))
    weights = (theta_w[:, None] * phi_w[None, :]).ravel()
    directions.flags.writeable = weights.flags.writeable = False
    return directions, weights


def _lobe_sums(
    radiance: np.ndarray, split: int, queries: np.ndarray, kernel
) -> npt.NDArray[np.float64]:
    """Σ over :func:`gauss_texels` points of kernel(⟨q, l⟩) L(l) dω for (s, 3) queries."""
    h, w = radiance.shape[:2]
    directions, weights = gauss_texels(h, w, split)
    texel = np.repeat(np.repeat(radiance, 3 * split, axis=0), 3 * split, axis=1)
    weighted = texel.reshape(-1, 3).astype(np.float64) * weights[:, None]
    out = np.zeros((len(queries), 3))
    for start in range(0, len(directions), _POINTS_PER_BLOCK):
        block = slice(start, start + _POINTS_PER_BLOCK)
        out += kernel(queries @ directions[block].T) @ weighted[block]
    return out


#: Quadrature points per block of :func:`_lobe_sums` (bounds its memory).
_POINTS_PER_BLOCK = 1 << 18
#: Largest point × sample product :func:`checked_error` spends (fewer samples past it).
_CHECK_BUDGET = 6e7


def brute_force_radiance(
    radiance: npt.ArrayLike,
    normals: npt.ArrayLike,
    views: npt.ArrayLike,
    values: dict[str, object],
    tangents: npt.ArrayLike | None = None,
) -> npt.NDArray[np.float64]:
    """:func:`exact_radiance` by a plain sum over quadrature points of every texel
    (:func:`gauss_texels`, :func:`brute_force_split`): slow, for checks. Same parameters;
    (s, 3) float64. Banks' normalisation is the same sum of its lobe (not the closed form
    the GPU pass takes)."""
    n = np.asarray(normals, dtype=np.float64)
    v = np.asarray(views, dtype=np.float64)
    exponent = float(values.get("phong_exponent", 1.0))
    fresnel = np.asarray(values["fresnel"], dtype=np.float64)
    _, reflections, diffuse, glossy = eq8_terms(n, v, fresnel, values["kd"])
    image = np.asarray(radiance, dtype=np.float32)
    out = np.zeros(diffuse.shape)
    if diffuse.any():
        out += diffuse * _lobe_sums(image, 1, n, lambda c: np.maximum(c, 0.0) / math.pi)
    if str(values.get("model", "phong")) == "phong":
        if glossy.any():
            out += glossy * _lobe_sums(
                image, texel_split(image.shape[0], exponent), reflections, _phong_lobe(exponent)
            )
        return out
    model = lobe_model(values)
    split = brute_force_split(image.shape[0], values)
    directions, weights = gauss_texels(*image.shape[:2], split)
    texel = np.repeat(np.repeat(image, 3 * split, axis=0), 3 * split, axis=1)
    weighted = texel.reshape(-1, 3).astype(np.float64) * weights[:, None]
    f0 = np.asarray(model.fresnel)
    for k in np.nonzero(np.einsum("sk,sk->s", n, v) > 0.0)[0]:
        total, norm = np.zeros(3), 0.0
        for start in range(0, len(directions), _POINTS_PER_BLOCK):
            block = slice(start, start + _POINTS_PER_BLOCK)
            if model.name == "banks":
                lobe, whole = banks_lobe(model, n[k], v[k], tangents[k], directions[block])
                norm += whole @ weights[block]
                total += lobe @ weighted[block]
            else:  # Schlick's F per channel: f_λ Σ s W + (1 − f_λ) Σ s m W
                scalar, schlick = microfacet_lobe(model, n[k], v[k], directions[block])
                total += f0 * (scalar @ weighted[block])
                total += (1.0 - f0) * ((scalar * schlick) @ weighted[block])
        if model.name == "banks":
            total *= glossy[k] / (norm if model.normalize else 1.0)
        out[k] += total
    return out


def brute_force_split(height: int, values: dict[str, object]) -> int:
    """Sub-texels per texel edge of :func:`brute_force_radiance`'s glossy sum for the
    reference's ``values``: :func:`texel_split` for Phong, each at most half of GGX's α."""
    model = str(values.get("model", "phong"))
    if model == "phong":
        return texel_split(height, float(values["phong_exponent"]))
    if model == "banks":  # a quarter of the band's half width acos(s): its edges are kinks
        width = 0.25 * math.acos(float(values["sharpness"]))
    else:
        width = ggx.alpha_for_exponent(float(values["phong_exponent"]))
    return int(min(16, max(1, math.ceil(2.0 * (math.pi / height) / width))))


def _phong_lobe(exponent: float):
    """c ↦ (N + 1)/2π max(c, 0)^N, evaluated only where it is above 10⁻¹⁵ of its peak (the
    rest, zero here, is below what float64 sums of the lobe's mass can hold)."""
    scale = (exponent + 1.0) / (2.0 * math.pi)
    floor = 1e-15 ** (1.0 / exponent)

    def lobe(c: np.ndarray) -> np.ndarray:
        out = np.zeros_like(c)
        inside = c > floor
        out[inside] = scale * c[inside] ** exponent
        return out

    return lobe


@dataclass(frozen=True)
class CheckedError:
    """An exact evaluation held against the brute force at some of its samples.

    Attributes
    ----------
    median, largest : float
        Median and largest relative difference (over each sample's largest channel).
    samples : int
        How many samples were checked.
    min_cos : float
        The smallest ⟨n, v⟩ checked: the brute force's parts are sized by GGX's α, so a
        microfacet sample seen more grazing than its lobe allows is not checked (its reflected
        lobe, about 2 α ⟨n, v⟩ wide, is narrower than two parts); 0 for the other models.
    """

    median: float
    largest: float
    samples: int
    min_cos: float = 0.0

    def describe(self) -> str:
        """ "12 samples" or "12 samples with ⟨n, v⟩ ≥ 0.31": where the check was taken."""
        where = f" with ⟨n, v⟩ ≥ {self.min_cos:.2g}" if self.min_cos > 0.0 else ""
        return f"{self.samples} samples{where}"


def checked_error(
    radiance: npt.ArrayLike,
    normals: npt.ArrayLike,
    views: npt.ArrayLike,
    computed: npt.ArrayLike,
    values: dict[str, object],
    samples: int = CHECKED_SAMPLES,
    tangents: npt.ArrayLike | None = None,
) -> CheckedError:
    """The relative differences of the ``computed`` (s, 3) radiance from the brute force
    (:func:`brute_force_radiance` of the reference's ``values``) at up to ``samples``
    facing samples spread evenly through the list (deterministic; fewer where the map is
    large, to keep the check's sums under :data:`_CHECK_BUDGET`).

    Each difference is over the sample's largest channel (a dark channel of a coloured
    sample is not divided by its own near-zero value). A microfacet sample is checked only
    where the brute force resolves its lobe (CheckedError.min_cos).
    """
    n = np.asarray(normals, dtype=np.float64)
    v = np.asarray(views, dtype=np.float64)
    image = np.asarray(radiance)
    split = brute_force_split(image.shape[0], values)
    min_cos = 0.0
    if str(values.get("model", "phong")) == "microfacet":
        part = math.pi / image.shape[0] / split
        min_cos = min(1.0, part / ggx.alpha_for_exponent(float(values["phong_exponent"])))
    facing = np.nonzero(np.einsum("sk,sk->s", n, v) > max(min_cos, 0.0))[0]
    if not len(facing):
        return CheckedError(0.0, 0.0, 0, min_cos)
    points = 9.0 * image.shape[0] * image.shape[1] * split**2
    samples = int(min(samples, max(8, _CHECK_BUDGET // points), len(facing)))
    picked = facing[np.linspace(0, len(facing) - 1, samples).astype(int)]
    t = None if tangents is None else np.asarray(tangents, dtype=np.float64)[picked]
    exact = brute_force_radiance(radiance, n[picked], v[picked], values, t)
    computed = np.asarray(computed, dtype=np.float64)[picked]
    scale = np.maximum(exact.max(axis=1), 1e-30)
    differences = np.abs(computed - exact).max(axis=1) / scale
    return CheckedError(float(np.median(differences)), float(differences.max()), samples, min_cos)


@dataclass
class ExactFrame:
    """The exact reference of one frame: per pixel, and the checked error.

    Attributes
    ----------
    hdr : (h, w, 3) float32
        Linear radiance, the mean over each pixel's covered samples; zero off the reflectors.
    mask : (h, w) bool
        Pixels with at least one covered sample.
    error : CheckedError
        :func:`checked_error` of the samples.
    seconds : float
        Wall time of the evaluation (the GL surface pass included).
    """

    hdr: npt.NDArray[np.float32]
    mask: npt.NDArray[np.bool_]
    error: CheckedError
    seconds: float


def exact_frame(
    normals: npt.NDArray[np.float32],
    views: npt.NDArray[np.float32],
    radiance: npt.ArrayLike,
    values: dict[str, object],
    ssaa: int,
    started: float | None = None,
    lobes: LobeEvaluator | None = None,
    tangents: npt.NDArray[np.float32] | None = None,
) -> ExactFrame:
    """The exact untraced frame from the reflectors' surface at ``ssaa``² samples a pixel.

    Parameters
    ----------
    normals, views : (h·ssaa, w·ssaa, 3) float32
        engine FrameRenderer.reflector_surface at the fine size (zero off the reflectors).
    radiance : (h, w, 3) array_like
        The lat-long environment the reference reads.
    values : dict
        The reference's parameter values (``model``, ``fresnel``, ``kd``, ``phong_exponent``).
    ssaa : int
        Samples per pixel per axis.
    started : float or None
        ``time.perf_counter()`` when the surface pass began (None: now).
    lobes : LobeEvaluator or None
        For a model in :data:`LOBE_MODELS`: its GPU integration.
    tangents : (h·ssaa, w·ssaa, 3) float32 or None
        model=banks: engine FrameRenderer.reflector_tangents at the fine size.
    """
    started = time.perf_counter() if started is None else started
    covered = np.linalg.norm(normals, axis=-1) > 0.5
    n, v = normals[covered], views[covered]
    t = None if tangents is None else tangents[covered]
    shaded = exact_radiance(radiance, n, v, values, lobes, t)
    error = checked_error(radiance, n, v, shaded, values, tangents=t)
    fine = np.zeros(normals.shape, dtype=np.float32)
    fine[covered] = shaded
    h, w = normals.shape[0] // ssaa, normals.shape[1] // ssaa
    weights = covered.reshape(h, ssaa, w, ssaa).astype(np.float64)
    count = weights.sum(axis=(1, 3))
    sums = fine.reshape(h, ssaa, w, ssaa, 3).astype(np.float64).sum(axis=(1, 3))
    hdr = (sums / np.maximum(count, 1.0)[..., None]).astype(np.float32)
    return ExactFrame(hdr, count > 0, error, time.perf_counter() - started)
