"""Cube mip chains on the GPU: filtered importance sampling, one pass per level and face.

The GPU twin of prefilter.chain.prefiltered_chain (the same levels, exponents
N_k = 2^(scale · g_k + bias) and ChainLevel results), after issue 14's "computed
on the GPU when a context is available". The lat-long source is uploaded with
its mip chain (``build_mipmaps``, 2×2 boxes); every level is one fragment pass
per face of shaders/prefilter/lobe_chain.glsl, which integrates the normalised
Phong lobe of seed 004 §4 (L_phong) by importance sampling with Křivánek and
Colbert's filtered importance sampling (FIS, "Real-time Shading with Filtered
Importance Sampling", EGSR 2008): sample s of pdf p_s stands for the solid angle
Ω_s = 1 / (S p_s) and is read from the source mip level

    lod_s = ½ log2(Ω_s / Ω_texel) + bias

with Ω_texel = (π / h)² for a lat-long of h rows (a row's angle squared; see the
shader on why not the texel's true solid angle) or (2 / n)² |l_ma|³ for a cube
of face n (``source_kind="cube"``: the lat-long resampled into a cube first,
envmap.conversions.latlong_to_cube; measured slightly less accurate and no
faster on llvmpipe, so not the default). The pdf is the kernel itself,
(N + 1)/2π cos^N θ, so every weight is 1: a constant map stays constant to
rounding, and wide lobes (few samples for a hemisphere) read coarse,
pre-averaged texels instead of aliasing.

The samples are one Fibonacci lattice in the lobe's frame, shared by every
texel (no noise; what remains is a smooth bias, measured against
prefilter.brute_force in studies/prefilter-speed/README.md). On studio.exr it was a
third to a half more accurate than a Hammersley set of the same size. Level k
takes S · 2^k samples (:func:`level_samples`). Faces under :data:`SPLIT_EDGE` texels are
drawn f × f times larger with the samples shared out among each texel's f × f fragments
(:func:`split_factor`), which the read-back adds up.

The same pass filters one level from a cube source (:func:`gpu_filtered_cube`): split-sum
GGX levels (:func:`ggx_lobe_samples`, Karis 2013) for method ``splitsum``, where the
samples are the reflections of r about GGX half vectors and each carries a weight (the
shader's second table row), ⟨r, l⟩ normalised over the set; or the Phong lobe, as above.
:func:`gpu_phong_cube_chain` fills a whole mip chain that way, one exponent per level
(:func:`texel_exponents`), for lookups at a fractional level (method ``parallax``).
"""

from __future__ import annotations

import math

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core import ggx
from envstudio.envmap.conversions import latlong_to_cube, upload_latlong
from envstudio.envmap.mipmaps import mipmapped_cube, write_cube_level
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.gpu.programs import ProgramLibrary
from envstudio.prefilter.chain import ChainLevel, gloss_exponents

__all__ = [
    "DEFAULT_SAMPLES",
    "FIS_BIAS",
    "MAX_SAMPLES",
    "SPLIT_EDGE",
    "ggx_lobe_samples",
    "gpu_filtered_cube",
    "gpu_phong_cube_chain",
    "gpu_prefiltered_chain",
    "level_samples",
    "lobe_samples",
    "source_face",
    "split_factor",
    "texel_exponents",
]

#: Importance samples per texel of level 0 (studies/prefilter-speed/README.md: the error against the
#: sample count); level k takes :func:`level_samples` of it.
DEFAULT_SAMPLES = 256
#: Most samples per texel at any level (the sample table's width, within every GL's texture limit).
MAX_SAMPLES = 16384
#: Added to every FIS level. Křivánek and Colbert add 1, trading aliasing for blur; with one
#: lattice for every texel there is no noise to hide, and on studio.exr 0 halved the error of
#: +1 at 256 samples, while −1 was worse again (studies/prefilter-speed/README.md).
FIS_BIAS = 0.0
_SHADER = "prefilter/lobe_chain.glsl"
#: A level whose face is smaller is drawn split (:func:`split_factor`), so that the rasteriser
#: (llvmpipe: 64 × 64-pixel tiles, one thread each) has several tiles to share out and each
#: fragment a shorter loop. Measured on llvmpipe, 8 levels from 128²: levels 1–7 drew in
#: 0.4 s instead of 0.8 s; larger edges drew faster still but read back and summed (m f)²
#: texels a face, and the chain came out slower (studies/prefilter-speed/README.md).
SPLIT_EDGE = 128


def lobe_samples(exponent: float, count: int, bias: float = FIS_BIAS) -> npt.NDArray[np.float32]:
    """A Fibonacci lattice of samples of the normalised Phong lobe with their FIS source level.

    Parameters
    ----------
    exponent
        Phong exponent N > 0.
    count
        S, the number of samples.
    bias
        Added to every level (Křivánek and Colbert use 1).

    Returns
    -------
    (count, 4) float32
        (x, y, z, lod): the direction in the lobe's frame (z = cos θ about the lobe
        axis), cos θ = u^(1/(N+1)) with u = (i + ½)/S and φ = 2π frac(i/ϕ) (ϕ the golden
        ratio: the spherical Fibonacci lattice, mapped through the lobe's inverse CDF), and
        lod = ½ log2 Ω_s + bias, Ω_s = 1 / (S p),
        p = (N + 1)/2π cos^N θ, before the shader takes off ½ log2 of the source texel's
        solid angle at the sample.
    """
    i = np.arange(count, dtype=np.float64)
    u = (i + 0.5) / count
    phi = 2.0 * np.pi * ((i * 0.5 * (math.sqrt(5.0) - 1.0)) % 1.0)
    cos = u ** (1.0 / (exponent + 1.0))
    sin = np.sqrt(np.maximum(0.0, 1.0 - cos * cos))
    # ln p = ln((N + 1)/2π) + N ln cos θ; cos θ ≥ u^(1/(N+1)) > 0.
    log2_pdf = (math.log((exponent + 1.0) / (2.0 * math.pi)) + exponent * np.log(cos)) / math.log(2)
    log2_omega_s = -math.log2(count) - log2_pdf
    lod = 0.5 * log2_omega_s + bias
    return np.stack([sin * np.cos(phi), sin * np.sin(phi), cos, lod], axis=1).astype(np.float32)


def ggx_lobe_samples(
    alpha: float, count: int, bias: float = FIS_BIAS
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
    """The split-sum GGX lobe about r (N = V = R) as a Fibonacci lattice with FIS levels.

    Karis (SIGGRAPH 2013 course) prefilters with n = v = r: half vectors h are drawn
    in proportion to D(h)(n·h) (core.ggx.half_vector_cosine at u = (i + ½)/S,
    φ = 2π frac(i/ϕ)), l = 2 (r·h) h − r is their reflection, and the radiance is
    Σ L(l) ⟨r, l⟩ / Σ ⟨r, l⟩ over the samples with ⟨r, l⟩ > 0. Since v·h = n·h, the
    density of l is D(h)/4, so Ω_s = 4 / (S D(h)) (Křivánek–Colbert's FIS level).

    Parameters
    ----------
    alpha
        GGX α in (0, 1].
    count
        S, the lattice's size (those below the horizon of r are left out).
    bias
        Added to every level.

    Returns
    -------
    table : (m, 4) float32
        (x, y, z, lod) as :func:`lobe_samples`, for the m ≤ S samples above the horizon.
    weights : (m,) float32
        ⟨r, l⟩ over their sum.
    """
    i = np.arange(count, dtype=np.float64)
    cos_h = ggx.half_vector_cosine((i + 0.5) / count, alpha)
    sin_h = np.sqrt(np.maximum(0.0, 1.0 - cos_h * cos_h))
    phi = 2.0 * np.pi * ((i * 0.5 * (math.sqrt(5.0) - 1.0)) % 1.0)
    z = 2.0 * cos_h * cos_h - 1.0
    keep = z > 0.0
    pdf = ggx.distribution(cos_h, alpha) / 4.0
    lod = 0.5 * (-math.log2(count) - np.log2(pdf)) + bias
    table = np.stack(
        [2.0 * cos_h * sin_h * np.cos(phi), 2.0 * cos_h * sin_h * np.sin(phi), z, lod], axis=1
    )[keep]
    weights = z[keep] / z[keep].sum()
    return table.astype(np.float32), weights.astype(np.float32)


def level_samples(samples: int, level: int) -> int:
    """Samples per texel at level k: S · 2^k, at most :data:`MAX_SAMPLES`.

    Each level has a quarter of the texels of the one above and a wider lobe over
    brighter, sharper detail (the map's lights), so doubling S per level halves
    the cost per level: the whole chain costs about twice its level 0.
    """
    return int(min(MAX_SAMPLES, samples << level))


def split_factor(face: int, count: int) -> int:
    """f: a face of ``face`` texels is drawn f × f times larger, f² ≤ ``count`` samples.

    Every fragment of a texel's f × f block sums every f²-th of its samples (the same
    samples, summed in another order: the result is the unsplit one to float rounding), so
    a small level is as many fragments as a large one: unsplit, a 1² face is one fragment on
    one llvmpipe thread, 20 times slower a sample than level 0 (studies/prefilter-speed/README.md).
    """
    f = max(1, SPLIT_EDGE // max(1, face))
    while f > 1 and f * f > count:
        f //= 2
    return f


def source_face(rows: int, size: int) -> int:
    """n_src: the power of two nearest the lat-long's h/2 rows (its texels' angle), at least n."""
    return max(size, 1 << max(0, round(math.log2(max(1, rows // 2)))))


def gpu_prefiltered_chain(
    ctx: moderngl.Context,
    programs: ProgramLibrary,
    radiance: npt.ArrayLike,
    size: int,
    levels: int,
    scale: float,
    bias: float,
    samples: int = DEFAULT_SAMPLES,
    *,
    fis_bias: float = FIS_BIAS,
    source_size: int | None = None,
    source_kind: str = "latlong",
) -> list[ChainLevel]:
    """Prefilter every level of the chain on the GPU (module docstring).

    Parameters
    ----------
    ctx, programs
        A context (OpenGL 3.3 or later) and its program library.
    radiance
        (h, 2h, 3) lat-long radiance.
    size
        Face edge n of level 0, a power of two.
    levels
        L, 1 ≤ L ≤ log2(n) + 1.
    scale, bias
        The glossiness mapping's constants (prefilter.chain.gloss_exponents).
    samples
        S, importance samples per texel of level 0 (level k: :func:`level_samples`).
    fis_bias
        Added to every sample's source level (:data:`FIS_BIAS`).
    source_size
        n_src, the source cube's face edge; default :func:`source_face`.
    source_kind
        ``"latlong"``: sample the lat-long texture and its mip chain directly;
        ``"cube"``: resample it into a cube of face n_src first.

    Returns
    -------
    list of ChainLevel
        Largest first, faces (6, n_k, n_k, 3) float32 in core.cubemap order, as
        prefilter.chain.prefiltered_chain returns them.
    """
    image = np.asarray(radiance, dtype=np.float32)
    rows = image.shape[0]
    latlong = upload_latlong(ctx, image)
    if source_kind == "cube":
        n_src = source_face(rows, size) if source_size is None else int(source_size)
        source = latlong_to_cube(ctx, programs, latlong, n_src)
        latlong.release()
        coarsest = n_src.bit_length() - 1
        texel_log2 = math.log2(2.0 / n_src)
    else:
        source = latlong
        source.build_mipmaps()
        source.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        coarsest = (2 * rows).bit_length() - 1
        texel_log2 = math.log2(math.pi / rows)
    program = programs.get(_SHADER, {"SOURCE": 0 if source_kind == "cube" else 1})
    quad = FullscreenPass(ctx)
    chain = []
    try:
        _bind_source(program, source, coarsest, texel_log2)
        for k, exponent in enumerate(gloss_exponents(levels, scale, bias)):
            count = level_samples(samples, k)
            table = lobe_samples(exponent, count, fis_bias)
            weights = np.full(count, 1.0 / count, np.float32)
            faces = _filter_level(ctx, program, quad, table, weights, max(1, size >> k))
            chain.append(ChainLevel(faces, exponent, rows))
    finally:
        quad.release()
        source.release()
    return chain


def gpu_filtered_cube(
    ctx: moderngl.Context,
    programs: ProgramLibrary,
    source: moderngl.TextureCube,
    size: int,
    lobe: float,
    samples: int,
    *,
    kernel: str = "ggx",
    fis_bias: float = FIS_BIAS,
) -> npt.NDArray[np.float32]:
    """One level filtered from a cube on the GPU: split-sum GGX or the Phong lobe.

    Parameters
    ----------
    ctx, programs
        A context (OpenGL 3.3 or later) and its program library.
    source
        Cube map with its full mip chain, trilinear (the static environment); its
        face edge is n_src, a power of two.
    size
        Face edge of the level.
    lobe
        GGX α in (0, 1] (``kernel="ggx"``, :func:`ggx_lobe_samples`) or the Phong
        exponent N > 0 (``kernel="phong"``, :func:`lobe_samples`).
    samples
        S, lattice points per texel.
    kernel
        ``"ggx"`` or ``"phong"``.
    fis_bias
        Added to every sample's source level.

    Returns
    -------
    (6, size, size, 3) float32
        The faces in core.cubemap order.
    """
    if kernel == "ggx":
        table, weights = ggx_lobe_samples(lobe, samples, fis_bias)
    elif kernel == "phong":
        table = lobe_samples(lobe, samples, fis_bias)
        weights = np.full(samples, 1.0 / samples, np.float32)
    else:
        raise ValueError(f"kernel {kernel!r}: expected 'ggx' or 'phong'")
    n_src = source.size[0]
    program = programs.get(_SHADER, {"SOURCE": 0})
    quad = FullscreenPass(ctx)
    try:
        _bind_source(program, source, float(n_src.bit_length() - 1), math.log2(2.0 / n_src))
        return _filter_level(ctx, program, quad, table, weights, size)
    finally:
        quad.release()


def texel_exponents(size: int) -> list[float]:
    """N_k = (n / 2^(k+1))² for the levels k = 0 … log2(n) of an n² cube mip chain.

    A Phong lobe cos^N θ is about σ = N^−½ radians wide (cos^N θ ≈ exp(−N θ²/2)), and a
    texel of level k, at a face's centre, 2^(k+1)/n: each level holds the lobe one of its
    texels wide, so its bilinear lookup widens it by about 8 % (the tent's σ, 0.41 texel,
    in quadrature) and no coarser level could hold it. The level of an exponent is then
    k(N) = log2(n) − 1 − ½ log2 N, fractional between levels (log-linear in N).
    """
    return [float((size / 2.0 ** (k + 1)) ** 2) for k in range(size.bit_length())]


def gpu_phong_cube_chain(
    ctx: moderngl.Context,
    programs: ProgramLibrary,
    source: moderngl.TextureCube,
    size: int,
    samples: int = DEFAULT_SAMPLES,
) -> moderngl.TextureCube:
    """A Phong-prefiltered mip chain of a cube: level k holds N_k of :func:`texel_exponents`.

    Parameters
    ----------
    ctx, programs
        A context (OpenGL 3.3 or later) and its program library.
    source
        Cube map with its full mip chain, trilinear (the probe's cube).
    size
        Face edge n of level 0, a power of two (at most the source's for a sharp level 0).
    samples
        S at level 0 (level k: :func:`level_samples`).

    Returns
    -------
    moderngl.TextureCube
        RGBA32F (alpha 1) with log2(n) + 1 levels, trilinear; the caller releases it.
    """
    chain = mipmapped_cube(ctx, size)
    try:
        for k, exponent in enumerate(texel_exponents(size)):
            faces = gpu_filtered_cube(
                ctx,
                programs,
                source,
                max(1, size >> k),
                exponent,
                level_samples(samples, k),
                kernel="phong",
            )
            write_cube_level(chain, k, faces)
    except BaseException:
        chain.release()
        raise
    return chain


def _bind_source(
    program: moderngl.Program,
    source: moderngl.Texture | moderngl.TextureCube,
    coarsest: float,
    texel_log2: float,
) -> None:
    """Bind ``source`` to unit 0 with its coarsest level and texel constant (lobe_chain.glsl)."""
    source.use(0)
    program["u_source"].value = 0
    program["u_source_max"].value = float(coarsest)
    program["u_texel_log2"].value = texel_log2
    program["u_table"].value = 1


def _filter_level(
    ctx: moderngl.Context,
    program: moderngl.Program,
    quad: FullscreenPass,
    table: npt.NDArray[np.float32],
    weights: npt.NDArray[np.float32],
    m: int,
) -> npt.NDArray[np.float32]:
    """The six (m, m, 3) faces of one level: ``table`` (S, 4) and ``weights`` (S,) drawn.

    Faces under :data:`SPLIT_EDGE` are drawn split (:func:`split_factor`) and their
    blocks added here.
    """
    count = len(table)
    rows = np.zeros((2, count, 4), np.float32)
    rows[0], rows[1, :, 0] = table, weights
    table_tex = ctx.texture((count, 2), 4, rows.tobytes(), dtype="f4")
    table_tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    split = split_factor(m, count)
    target = ctx.texture((m * split, m * split), 4, dtype="f4")
    fbo = ctx.framebuffer([target])
    scope = ctx.scope(fbo, enable_only=moderngl.NOTHING)
    try:
        table_tex.use(1)
        program["u_count"].value = count
        program["u_size"].value = float(m)
        program["u_split"].value = split
        faces = []
        with scope:
            for face in range(6):
                program["u_face"].value = face
                quad.draw(program)
                data = fbo.read(components=3, dtype="f4")
                shares = np.frombuffer(data, np.float32).reshape(m, split, m, split, 3)
                faces.append(shares.sum(axis=(1, 3), dtype=np.float64).astype(np.float32))
    finally:
        for obj in (scope, fbo, target, table_tex):
            obj.release()
    return np.stack(faces)
