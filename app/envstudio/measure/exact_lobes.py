"""The exact untraced glossy term of the models whose lobe depends on (n, v) or (v, t)
together: ``microfacet`` and ``banks`` (the reference's models 1 and 2).

Their lobe is not a function of one direction, so no prefiltered map holds it; at each
footprint sample the term is the integral of the environment against the lobe,

    microfacet:  ∫ L(l) D(h) G2(l, v) F(v·h) / (4 ⟨n, v⟩) dl over ⟨n, l⟩ > 0,
    banks:       F(⟨n, v⟩) c ∫ L(l) f_banks(⟨l, t⟩, ⟨v, t⟩) [max(⟨n, l⟩, 0)] dl,

(shaders/reference/material.glsl, accumulate.glsl), the environment a function constant
over each lat-long texel, as the Monte Carlo reference sees it. A compute pass
(shaders/reference/exact_lobe.glsl) evaluates it by seed 004 §5.1's descent of the
environment's mip pyramid (prefilter.hierarchical.source_pyramid): a node is taken at its
radiance moments where the lobe is smooth over it (a three-point rule exact for quadratics;
for GGX its cap in half-vector space under :data:`ACCEPT` times max(α, twice its distance
to n: the tail, a power of that distance, takes nodes twice as wide as the peak would),
and across the horizon ⟨n, l⟩ = 0, where G2 has a kink, finer still where the lobe rises
steeply from it; for Banks under 1.5 :data:`ACCEPT` times the band's half width inside the
band and :data:`ACCEPT` times it across its edges, where the lobe has a kink), skipped
where the lobe is zero over it, refined otherwise, and a texel still refined is cut into
parts finer than the lobe. A GGX lobe narrower across than a texel's finest part (a grazing
view of a sharp lobe) has its peak taken over half vectors instead, by a second pass (cells
of equal GGX probability, each reading its texel), the descent taking the rest. What that
leaves out is measured, not assumed:
exact_reference.checked_error holds the result against a plain sum over Gauss points of
every texel
(exact_reference.brute_force_radiance, with :func:`microfacet_lobe` and :func:`banks_lobe`),
the same anchor as the ``phong`` model's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core import ggx, latlong
from envstudio.errors import ParameterError
from envstudio.gpu.programs import ProgramLibrary
from envstudio.gpu.uniforms import set_uniform
from envstudio.prefilter.hierarchical import source_pyramid

#: A node is accepted when its cap is under this fraction of the lobe's width there.
ACCEPT = 0.1
#: Iterations a dispatch spends on a sample at most (llvmpipe ends an invocation's loops
#: after 65 535 iterations; a texel cut into parts takes up to 16² at once).
BUDGET = 60000
#: A node brighter than the map's mean (a sun) errs in proportion to its radiance, so its
#: acceptance scale shrinks by this power (the cube root) of how much brighter it is (the
#: three-point rule errs as the cube of the node's size over the lobe's scale). Against the
#: NumPy sum on a sphere under a small sun (32 × 64 map, 2 × 2-texel sun at 2000, 584 pixel
#: centres): at most 0.08 % instead of 1.14 % (a pixel whose horizon held the sun); 1–5 %
#: more time on the sunrise sphere at 96 × 96 × 16.
BRIGHT_POWER = 1.0 / 3.0
#: Samples per dispatch.
SAMPLES_PER_DISPATCH = 1 << 14
#: Nodes of the level the descent starts at, at least.
START_NODES = 32
#: Texels of the largest environment the pyramid takes (2048 × 1024: about 110 MB of textures
#: and 0.9 GB while it is built).
MAX_TEXELS = 2048 * 1024


def check_size(height: int, width: int) -> None:
    """Refuse a map too large for the pyramid, naming the ``--max-env-width`` that fits.

    Raises
    ------
    ParameterError
        Above :data:`MAX_TEXELS`.
    """
    if height * width > MAX_TEXELS:
        fits = width
        while height * fits * fits // width > MAX_TEXELS:
            fits //= 2
        raise ParameterError(
            f"environment {width}x{height}: too large for the exact reference's tables (at "
            f"most {MAX_TEXELS} texels); pass --max-env-width {fits} (or --reference montecarlo)"
        )


_MODELS = {"microfacet": 1, "banks": 2}
#: The pyramid's textures in PyramidTextures.textures, by their names in exact_lobe.glsl.
TEXTURE_NAMES = ("u_radiance", "u_direction", "u_point0", "u_point1", "u_point2")


@dataclass(frozen=True)
class LobeModel:
    """The parameters of one glossy model, as the reference's values give them.

    Attributes
    ----------
    name : str
        ``microfacet`` or ``banks``.
    fresnel : (3,) tuple of float
        f_λ, linear RGB.
    alpha : float
        GGX roughness (microfacet).
    sharpness : float
        Banks' s (banks).
    normalize, self_shadowing : bool
        Banks' ``normalize`` (divide by the lobe's integral) and the ⟨n, l⟩ factor.
    """

    name: str
    fresnel: tuple[float, float, float]
    alpha: float = 0.0
    sharpness: float = 0.0
    normalize: bool = False
    self_shadowing: bool = False


def band_table(height: int, width: int) -> npt.NDArray[np.float32]:
    """Level 0's rows and columns as exact_lobe.glsl's ``bands`` holds them.

    Returns
    -------
    (height + width, 4) float32
        Row r: cos θ₀, sin θ₀ of its upper edge θ₀ = π r / height, its texels' solid angle
        (sr), 0. Column c: cos φ₀, sin φ₀ of its left edge φ₀ = 2π (c / width − ½), 0, 0.
    """
    table = np.zeros((height + width, 4))
    theta = np.pi * np.arange(height) / height
    table[:height, 0], table[:height, 1] = np.cos(theta), np.sin(theta)
    table[:height, 2] = latlong.texel_solid_angles(height, width)[:, 0]
    phi = 2.0 * np.pi * (np.arange(width) / width - 0.5)
    table[height:, 0], table[height:, 1] = np.cos(phi), np.sin(phi)
    return table.astype(np.float32)


def node_points(samples: np.ndarray, spreads: np.ndarray) -> np.ndarray:
    """The three points of each node's three-point rule (exact_lobe.glsl's lobe_mean).

    The rule integrates every quadratic exactly over a distribution of directions with
    centroid s and second moment (a, b; b, c) about it in the plane (e1, e2) across s: the
    points s + √2 C z_k, z_k the unit vectors at 0°, 120° and 240° and C Cᵀ = (a, b; b, c)
    (Cholesky), each taken as l / |l| (the lobe constant along rays). They depend on the
    node alone, not on the sample, so they are computed once here.

    Parameters
    ----------
    samples : (3, n) array_like
        The nodes' radiance centroids s (not normalised).
    spreads : (6, n) array_like
        Their second moments about s over their weight: xx, yy, zz, 2xy, 2xz, 2yz.

    Returns
    -------
    (3, n, 3) float64
        The three unit directions of each node.
    """
    s = np.asarray(samples, np.float64)
    xx, yy, zz, xy, xz, yz = np.asarray(spreads, np.float64)

    def form(u, w):  # uᵀ S w, column by column
        return (
            xx * u[0] * w[0]
            + yy * u[1] * w[1]
            + zz * u[2] * w[2]
            + 0.5 * xy * (u[0] * w[1] + u[1] * w[0])
            + 0.5 * xz * (u[0] * w[2] + u[2] * w[0])
            + 0.5 * yz * (u[1] * w[2] + u[2] * w[1])
        )

    d = s / np.maximum(np.linalg.norm(s, axis=0), 1e-30)
    # e1 = d × y where |d_y| < 0.9, d × x elsewhere; e2 = d × e1
    y_axis = np.abs(d[1]) < 0.9
    e1 = np.where(y_axis, [-d[2], np.zeros_like(d[0]), d[0]], [np.zeros_like(d[0]), d[2], -d[1]])
    e1 /= np.linalg.norm(e1, axis=0)
    e2 = np.cross(d, e1, axis=0)
    l11 = np.sqrt(np.maximum(form(e1, e1), 0.0))
    l21 = np.divide(form(e1, e2), l11, out=np.zeros_like(l11), where=l11 > 0.0)
    l22 = np.sqrt(np.maximum(form(e2, e2) - l21 * l21, 0.0))
    c1 = math.sqrt(2.0) * (l11 * e1 + l21 * e2)
    c2 = math.sqrt(2.0) * l22 * e2
    half = math.sqrt(3.0) / 2.0
    points = np.stack([s + c1, s - 0.5 * c1 + half * c2, s - 0.5 * c1 - half * c2])
    points /= np.maximum(np.linalg.norm(points, axis=1, keepdims=True), 1e-30)
    return np.swapaxes(points, 1, 2)


class PyramidTextures:
    """The environment's pyramid on the GPU, as exact_lobe.glsl reads it: per level W and ρ,
    d and the acceptance's shrink for a bright node, the three points of the node's rule
    (:func:`node_points`); and :func:`band_table`'s storage buffer.

    Parameters
    ----------
    ctx : moderngl.Context
    radiance : (h, w, 3) array_like
        The lat-long environment, linear radiance; h and w powers of two (w = 2h).

    Raises
    ------
    ParameterError
        A map above :data:`MAX_TEXELS` (:func:`check_size`).
    """

    def __init__(self, ctx: moderngl.Context, radiance: npt.ArrayLike):
        check_size(*np.shape(radiance)[:2])
        pyramid = source_pyramid(radiance)
        h, w = pyramid.shapes[0]
        self.size = (w, h)
        self.levels = levels = len(pyramid.shapes)
        self.start_level = next(
            (k for k in range(levels - 1, -1, -1) if np.prod(pyramid.shapes[k]) >= START_NODES),
            0,
        )
        # a texel's own half-diagonal, so a level-0 cap covers the texel's area
        texel = math.hypot(0.5 * math.pi / h, math.pi / w)
        textures = [ctx.texture((w, h), 4, dtype="f4") for _ in range(5)]
        for texture in textures:  # allocates the chain; every level is written below
            texture.build_mipmaps(0, levels - 1)
        # the map's mean radiance over the sphere, its largest channel (Σ W / 4π)
        top = np.asarray(pyramid.radiance[levels - 1]).reshape(3, -1).sum(axis=1)
        mean_radiance = max(top.max(), 1e-30) / (4.0 * math.pi)
        bands = band_table(h, w)
        texel_area = np.repeat(bands[:h, 2], w)
        for level, (rows, cols) in enumerate(pyramid.shapes):
            cos_rho, sin_rho = pyramid.radii[level]
            rho = (np.arctan2(sin_rho, cos_rho) * (level > 0) + texel).astype(np.float32)
            # the node's mean radiance over the map's (its area a texel's or its cap's): the
            # acceptance shrinks by its BRIGHT_POWER
            area = texel_area if level == 0 else np.pi * rho.astype(np.float64) ** 2
            brightest = np.asarray(pyramid.radiance[level], np.float64).max(axis=0)
            shrink = np.maximum(brightest / (area * mean_radiance), 1.0) ** BRIGHT_POWER
            points = node_points(pyramid.samples[level], pyramid.spreads[level])
            zeros = np.zeros_like(rho)
            planes = (
                (*pyramid.radiance[level], rho),
                (*pyramid.directions[level], shrink),
                *((*point.T, zeros) for point in points),
            )
            for texture, plane in zip(textures, planes, strict=True):
                data = np.stack(plane, axis=-1).reshape(rows, cols, 4).astype(np.float32)
                texture.write(np.ascontiguousarray(data), level=level)
        for texture in textures:
            texture.filter = (moderngl.NEAREST_MIPMAP_NEAREST, moderngl.NEAREST)
        self.textures = textures
        self.bands = ctx.buffer(bands.tobytes())

    def release(self) -> None:
        for texture in self.textures:
            texture.release()
        self.bands.release()


class LobeEvaluator:
    """:func:`glossy_term` on one context, with the pyramid of the last environment kept.

    Parameters
    ----------
    ctx : moderngl.Context
    programs : ProgramLibrary
    """

    def __init__(self, ctx: moderngl.Context, programs: ProgramLibrary):
        self.ctx, self.programs = ctx, programs
        self._radiance: np.ndarray | None = None
        self._textures: PyramidTextures | None = None

    def glossy(
        self,
        radiance: np.ndarray,
        model: LobeModel,
        normals: npt.ArrayLike,
        views: npt.ArrayLike,
        tangents: npt.ArrayLike | None = None,
    ) -> npt.NDArray[np.float64]:
        """:func:`glossy_term` under the lat-long ``radiance`` (h, w, 3)."""
        if self._radiance is not radiance:
            self.release()
            self._textures = PyramidTextures(self.ctx, radiance)
            self._radiance = radiance
        return glossy_term(self.ctx, self.programs, self._textures, model, normals, views, tangents)

    def release(self) -> None:
        """Free the pyramid's textures."""
        if self._textures is not None:
            self._textures.release()
        self._radiance = self._textures = None


def glossy_term(
    ctx: moderngl.Context,
    programs: ProgramLibrary,
    textures: PyramidTextures,
    model: LobeModel,
    normals: npt.ArrayLike,
    views: npt.ArrayLike,
    tangents: npt.ArrayLike | None = None,
    accept: float = ACCEPT,
) -> npt.NDArray[np.float64]:
    """The glossy term of ``model`` at each sample (module docstring).

    Parameters
    ----------
    normals, views : (s, 3) array_like
        Unit shading normals (turned to the seen side) and directions to the camera.
    tangents : (s, 3) array_like or None
        Unit tangents orthogonal to the normals (banks).
    accept : float
        The descent's acceptance ratio (:data:`ACCEPT`).

    Returns
    -------
    (s, 3) float64
        Radiance; zero where ⟨n, v⟩ ≤ 0.
    """
    n = np.asarray(normals, dtype=np.float32).reshape(-1, 3)
    count = len(n)
    if not count:
        return np.zeros((0, 3))

    def padded(vectors):
        out = np.zeros((count, 4), np.float32)
        out[:, :3] = vectors
        return ctx.buffer(out.tobytes())

    buffers = [
        padded(n),
        padded(np.asarray(views, dtype=np.float32).reshape(-1, 3)),
        padded(np.zeros((count, 3)) if tangents is None else tangents),
        ctx.buffer(reserve=16 * count),
    ]
    buffers[3].clear()
    w, h = textures.size
    start_nodes = (w >> textures.start_level) * (h >> textures.start_level)
    stack_size = start_nodes + 3 * textures.levels + 4
    chunk = min(count, SAMPLES_PER_DISPATCH)
    stacks = ctx.buffer(reserve=16 * stack_size * chunk)
    tops = ctx.buffer(reserve=4 * chunk)
    # the model a compile-time constant: llvmpipe would run both models' branches otherwise
    defines = {"STACK_SIZE": stack_size, "MODEL": _MODELS[model.name]}
    shader = programs.compute("reference/exact_lobe.glsl", defines)
    passes = [shader]
    if model.name == "microfacet":  # the peak caps of lobes narrower than a texel's part
        passes.append(programs.compute("reference/exact_lobe.glsl", {**defines, "PEAK_PASS": 1}))
    for binding, buffer in enumerate([*buffers, stacks, tops, textures.bands]):
        buffer.bind_to_storage_buffer(binding)
    for unit, texture in enumerate(textures.textures):
        texture.use(unit)
    uniforms = {
        **{name: unit for unit, name in enumerate(TEXTURE_NAMES)},
        "u_level0": textures.size,
        "u_start_level": textures.start_level,
        "u_accept": accept,
        "u_alpha": model.alpha,
        "u_fresnel": model.fresnel,
        "u_sharpness": model.sharpness,
        "u_banks_normalize": model.normalize,
        "u_self_shadowing": model.self_shadowing,
        "u_budget": BUDGET,
    }
    for program in passes:
        for name, value in uniforms.items():
            set_uniform(program, name, value)
    for first in range(0, count, chunk):
        samples = min(chunk, count - first)
        tops.write(np.full(chunk, -1, np.int32).tobytes())
        for program in passes:
            set_uniform(program, "u_first_sample", first)
            set_uniform(program, "u_samples", samples)
        while True:
            shader.run(group_x=(samples + 63) // 64)
            if not np.frombuffer(tops.read(), np.int32)[:samples].any():
                break
        for peaks in passes[1:]:
            ctx.memory_barrier()
            peaks.run(group_x=(samples + 63) // 64)
    out = np.frombuffer(buffers[3].read(), np.float32).reshape(count, 4)[:, :3]
    for buffer in (*buffers, stacks, tops):
        buffer.release()
    return out.astype(np.float64)


def microfacet_lobe(
    model: LobeModel, normals: np.ndarray, views: np.ndarray, directions: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """D G2 F(v·h) / (4 ⟨n, v⟩) at (p, 3) directions for one sample, in two factors: the lobe
    is ``scalar`` × (f_λ + (1 − f_λ) ``schlick``) per channel (Schlick's F), so that a sum
    over many directions takes two dot products instead of a (p, 3) array.

    Returns
    -------
    scalar : (p,) float64
        D G2 / (4 ⟨n, v⟩); zero where ⟨n, l⟩ ≤ 0.
    schlick : (p,) float64
        (1 − ⟨v, h⟩)⁵.
    """
    cosines = directions @ np.stack([normals, views], axis=1)
    n_dot_l, v_dot_l = cosines[:, 0], cosines[:, 1]
    n_dot_v = float(views @ normals)
    # h = (l + v) / |l + v| and |l + v|² = 2 + 2 ⟨v, l⟩
    inverse = 1.0 / np.sqrt(np.maximum(2.0 + 2.0 * v_dot_l, 1e-300))
    # a cosine: clipped to 1 where l = −v leaves h undefined (there ⟨n, l⟩ = −⟨n, v⟩ < 0)
    d = ggx.distribution(np.clip((n_dot_l + n_dot_v) * inverse, 0.0, 1.0), model.alpha)
    g2 = ggx.smith_g2(n_dot_l, n_dot_v, model.alpha)
    scalar = np.where(n_dot_l > 0.0, d * g2 / (4.0 * n_dot_v), 0.0)
    schlick = (1.0 - np.clip((v_dot_l + 1.0) * inverse, 0.0, 1.0)) ** 5
    return scalar, schlick


def banks_lobe(
    model: LobeModel,
    normals: np.ndarray,
    views: np.ndarray,
    tangents: np.ndarray,
    directions: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Banks' lobe (seed 004 §5.3, banks_brdf.glsl) at (p, 3) directions for one sample.

    Returns
    -------
    lobe : (p,) float64
        f_banks(⟨l, t⟩, ⟨v, t⟩) [max(⟨n, l⟩, 0) with self-shadowing], the same in every
        channel.
    whole : (p,) float64
        f_banks alone: what its integral over the sphere (the normalisation) sums.
    """
    lt = directions @ tangents
    vt = float(views @ tangents)
    s = model.sharpness
    bracket = np.sqrt(np.maximum(1.0 - lt * lt, 0.0)) * math.sqrt(max(1.0 - vt * vt, 0.0))
    whole = np.maximum(bracket - lt * vt - s, 0.0) / (1.0 - s) ** 2
    lobe = whole * np.maximum(directions @ normals, 0.0) if model.self_shadowing else whole
    return lobe, whole
