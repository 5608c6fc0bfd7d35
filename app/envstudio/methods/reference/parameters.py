"""The reference's parameters, and which of them only schedule the accumulation."""

from __future__ import annotations

from dataclasses import replace

from envstudio.methods.reference.sample_allocation import MAX_MULTIPLIER
from envstudio.plugin import MAX_TIME_LIMIT_S, Parameter, fresnel_parameter, kd_parameter
from envstudio.shading.materials import BANKS_MATERIAL_PARAMETERS

MODELS = ("phong", "microfacet", "banks")
SEQUENCES = ("random", "sobol")
ENVIRONMENT_SAMPLING = ("auto", "global", "lobe")
#: Parameters that decide when to stop and how a batch is split into draws, not
#: what is estimated: changing one continues the accumulation, and the saved
#: accumulations' keys leave them out (measure/ground_truth_cache.py).
SCHEDULING_PARAMETERS = ("max_samples", "tolerance", "time_limit", "samples_per_draw")

REFERENCE_PARAMETERS = (
    Parameter(
        "model",
        "choice",
        "phong",
        choices=MODELS,
        rebuild=False,
        help="phong: seed 000 eq. 8 (diffuse + Phong, Schlick); microfacet: GGX; banks: "
        "seed 004 §5.3's Banks lobe about the tangent field (diffuse + Banks, Schlick).",
    ),
    *(replace(p, applies_when={"model": "banks"}) for p in BANKS_MATERIAL_PARAMETERS),
    Parameter(
        "self_shadowing",
        "bool",
        False,
        help="model=banks: keep the term ⟨n,l⟩ (and the hemisphere) that method banks "
        "drops (seed 004 §5.3); off: the whole sphere, as the 3D map.",
        applies_when={"model": "banks"},
    ),
    fresnel_parameter(1.0, "Schlick reflectance at normal incidence, per RGB channel."),
    kd_parameter(0.0, "Diffuse albedo, per RGB channel."),
    Parameter(
        "phong_exponent",
        "float",
        200.0,
        0.01,
        1_000_000.0,
        "N",
        "Phong exponent (microfacet: alpha = sqrt(2 / (4N + 2)); N < 1 reaches alpha 0.58 … "
        "0.995).",
        log=True,
        applies_when={"model": ("phong", "microfacet")},
    ),
    Parameter(
        "trace",
        "bool",
        True,
        rebuild=True,
        help="Trace the scene's triangles: self-occlusion, local and self-reflections.",
    ),
    Parameter(
        "untraced_too",
        "bool",
        False,
        rebuild=True,
        help="With trace: also accumulate the untraced estimate (the environment-map model) "
        "from the same samples (with trace only): compare's approximation error at no "
        "second run.",
    ),
    Parameter(
        "pixel_filter",
        "bool",
        True,
        help="Average each pixel's footprint (anti-aliased, as mip-mapped methods see it); "
        "off: the pixel centre only.",
    ),
    Parameter(
        "sequence",
        "choice",
        "sobol",
        choices=SEQUENCES,
        help="sobol: one scrambled Sobol sequence per pixel (faster convergence; the "
        "standard error shown is then an upper bound); random: independent batches.",
    ),
    Parameter(
        "environment_sampling",
        "choice",
        "auto",
        choices=ENVIRONMENT_SAMPLING,
        help="lobe: draw the glossy term's environment samples by luminance inside the "
        "lobe's cap (small lamps converge faster); global: from the whole map (better where "
        "local objects hide the environment); auto: global when tracing a scene with local "
        "objects, else lobe.",
    ),
    Parameter("samples", "int", 8, 1, 256, "spp/frame", "Estimates per pixel added each frame."),
    Parameter(
        "adaptive",
        "bool",
        True,
        help="At every doubling, give each pixel 1-4 x `samples` per frame in proportion to "
        "its standard error (more where the image is noisy).",
    ),
    Parameter(
        "samples_per_draw",
        "int",
        0,
        0,
        256 * MAX_MULTIPLIER,
        "spp",
        "Estimates a pixel adds per draw call; a batch takes as many draws as it needs. "
        "0: the whole batch in one draw on GPUs, 32 on software renderers (their loop limit, "
        "which also caps other values). Smaller chunks keep more draws in flight on a GPU; "
        "the samples are the same.",
    ),
    Parameter(
        "max_samples",
        "int",
        8192,
        1,
        10_000_000,
        "spp",
        "Sample budget per pixel; beyond it the result is reported as not converged.",
    ),
    Parameter(
        "tolerance",
        "float",
        0.001,
        1e-5,
        0.1,
        "",
        "Converged when the successive-half RMS change is below this.",
        log=True,
    ),
    Parameter(
        "time_limit",
        "float",
        0.0,
        0.0,
        MAX_TIME_LIMIT_S,
        "s",
        "Time budget: stop accumulating this many seconds after the (re)start, reported as "
        "not converged unless it converged first (0: no limit).",
        log=True,
    ),
)
