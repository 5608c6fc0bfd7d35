"""``envstudio compare``: methods against the reference at matched parameters.

Steps, in one :class:`RenderSession` (one camera, one size, one display setting):

1. Each method renders the same frame (until :meth:`Method.finished`); its
   linear HDR frame and its display image are kept.
2. The ground truth (the plugin declared ``ground_truth``: methods/reference/)
   accumulates until the stopping rule holds (measure/stopping.py): by default
   until its noise is under a tenth of every method's error against it (judged
   at its checkpoints), strictly
   until its successive-half change is below ``tolerance``; under either rule
   it also stops on its sample budget (``max_samples``) or time limit
   (``time_limit``). A progress line shows the noise, each method's error and
   the time left. Its coverage is the reflector mask; an empty mask (the
   camera sees no reflector) is an error. With the cache on (the CLI's
   default), the accumulation is saved as it goes and a later run with the
   same inputs resumes it (measure/ground_truth_cache.py).
3. Every method is measured against the reference with core/metrics.py
   (PSNR, SSIM, FLIP on the display images over the mask).
4. Each method is timed by the bench code path (measure/bench.py: wall clock
   with ``ctx.finish()`` at both ends, median of ``frames`` frames after
   ``warmup``); the reference's time per frame is the median of its own
   accumulation frames, measured the same way.

Parameter matching
    Every method starts from the scene's material (RenderSession). ``--param
    name=value`` goes to every method of the comparison that declares ``name``,
    the reference included, and to the display settings; the others ignore it.
    A name that no method and no display setting declares is an error. A method
    that blurs a mip chain by a LOD bias (declares ``lod_bias`` but not
    ``phong_exponent``) gets the b that looks like the reference's Phong
    exponent N on this session's cube (prefilter/glossiness.py), unless
    ``--param lod_bias=…`` sets it. A method with a GGX ``roughness`` gets the α of the
    reference's N (α = √(2 / (4N + 2))), unless ``--param roughness=…`` sets it; the
    reference of its group then takes the N of that α.

Reliability
    A method's metrics are reliable when the reference converged or its noise
    is under :data:`NOISE_SHARE` of the method's median relative error
    (:func:`_judge`). A reference stopped by its budget or time limit before
    that still carries Monte Carlo noise that is part of the metrics: they are
    marked unreliable and the reason is given
    (:attr:`ReferenceRun.unreliable_reason`).
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import numpy.typing as npt

from envstudio.core.metrics import ImageMetrics, compare_images, relative_error
from envstudio.core.parameters import parse_assignments
from envstudio.engine.display import DISPLAY_PARAMETERS
from envstudio.engine.method import Method, ReportExtra
from envstudio.engine.registry import ground_truth_class, method_class
from envstudio.engine.session import RenderSession
from envstudio.errors import ParameterError
from envstudio.gpu.context import describe
from envstudio.measure.bench import run_bench
from envstudio.measure.exact_lobes import LobeEvaluator
from envstudio.measure.exact_reference import EXACT_MODELS
from envstudio.measure.ground_truth import (
    SCENE_EFFECTS,
    UNTRACED_TOO,
    GroundTruth,
)
from envstudio.measure.matching import match_glossiness, match_roughness
from envstudio.measure.reference_runs import (
    EXACT,
    ReferenceRun,
    converge,
    display_image,
    exact_run,
    untraced_run,
)
from envstudio.measure.stopping import (
    NOISE_SHARE,
    ReferenceJudge,
    choose_rule,
    control_variate_uncertainty,
    median_error,
)

MATCHED_NAMES = ("model", "fresnel", "kd", "phong_exponent", "lod_bias")
"""Parameters listed as "matched" in the report when a method declares them."""


@dataclass(frozen=True)
class ParameterPlan:
    """Validated ``--param`` values, per method and for the display.

    Attributes
    ----------
    methods : dict
        Method name → {parameter name → value} for the names that method declares.
    display : dict
        Display setting → value.
    """

    methods: dict[str, dict[str, object]]
    display: dict[str, object]


#: Samples per axis ``ssaa`` may ask for, and the largest supersampled frame edge.
MAX_SSAA = 8
MAX_SSAA_EDGE = 8192


def check_ssaa(ssaa: object, size: tuple[int, int], name: str = "ssaa") -> None:
    """Refuse a supersampling that compare cannot render (compare, atlas and the API alike).

    Parameters
    ----------
    ssaa
        Samples per pixel per axis, as given.
    size : (int, int)
        The frame's width and height, pixels.
    name
        How the caller calls it (``--ssaa`` on the command line).

    Raises
    ------
    ParameterError
        Unless ``ssaa`` is an integer in 1..:data:`MAX_SSAA` with ``ssaa`` × the larger
        edge of ``size`` at most :data:`MAX_SSAA_EDGE` pixels.
    """
    edge = max(size)
    is_int = isinstance(ssaa, int) and not isinstance(ssaa, bool)
    if not is_int or not 1 <= ssaa <= MAX_SSAA or ssaa * edge > MAX_SSAA_EDGE:
        raise ParameterError(
            f"{name} {ssaa!r}: expected an integer in 1..{MAX_SSAA} with "
            f"{name} x {edge} <= {MAX_SSAA_EDGE} pixels"
        )


@dataclass
class MethodResult:
    """One method's frame and how it compares.

    Attributes
    ----------
    name : str
        Method name.
    parameters : dict
        Its parameter values as rendered.
    matched : dict
        The material parameters it declares (:data:`MATCHED_NAMES`) and their values.
    glossiness : str or None
        How ``lod_bias`` was matched to the reference's N, when it was.
    metrics : ImageMetrics
        Against the reference, over the mask.
    relative_error : (h, w) float32
        Per-pixel relative luminance error of the linear frames.
    frame_ms : dict
        ``median_ms`` and ``p95_ms`` of the time per frame.
    timing : str
        How ``frame_ms`` was measured.
    hdr : (h, w, 3) float32
        Linear radiance of the frame.
    display : (h, w, 3) float32
        The frame as displayed, in [0, 1].
    reference_model : str or None
        The reflectance model of the reference it was measured against (None: the
        ground truth renders no reference of its model, and it has no numbers).
    approximation : ImageMetrics or None
        Against the untraced reference of its model (the environment-map model the
        technique approximates), when the reference traces; ``metrics`` is then
        the scene error, against the traced one.
    approximation_error : float
        Median relative error against the untraced reference (NaN without one).
    scene_only_error : float
        Median relative error of the untraced reference against the traced one: what
        no environment map shows (NaN without an untraced reference).
    missing_input : str or None
        Why the frame is a stand-in, not the technique (Method.missing_input: pem
        without a bake for the scene); it then has no numbers and is not reliable.
    """

    name: str
    parameters: dict[str, object]
    matched: dict[str, object]
    glossiness: str | None
    metrics: ImageMetrics
    relative_error: npt.NDArray[np.float32]
    frame_ms: dict[str, float]
    timing: str
    hdr: npt.NDArray[np.float32]
    display: npt.NDArray[np.float32]
    median_relative_error: float = float("nan")
    reliable: bool = True
    reference_model: str | None = None
    approximation: ImageMetrics | None = None
    approximation_error: float = float("nan")
    scene_only_error: float = float("nan")
    missing_input: str | None = None


@dataclass
class Comparison:
    """Everything ``envstudio compare`` reports.

    Attributes
    ----------
    scene : str
        Scene name.
    size : (int, int)
        Width, height in pixels.
    camera : (float, float, float)
        Azimuth, elevation (degrees), distance (scene units).
    display : dict
        Display settings the display images were made with.
    device : str
        GL renderer and version.
    mask : (h, w) bool
        The reflector pixels (the reference's coverage).
    reference : ReferenceRun
    results : list of MethodResult
        In the order asked for.
    extras : dict
        Method name → the sections it adds to the report (:meth:`Method.report_extras`;
        only methods that add some).
    ssaa : int
        Samples per pixel each method was box-filtered from, per axis (1: pixel centres).
    references : dict
        Reflectance model → its reference (``reference`` is the first), one per model of
        the methods compared.
    untraced : dict
        Reflectance model → its untraced reference, for the models whose reference
        traces (empty with ``--no-decompose`` or an untraced reference).
    """

    scene: str
    size: tuple[int, int]
    camera: tuple[float, float, float]
    display: dict[str, object]
    device: str
    mask: npt.NDArray[np.bool_]
    reference: ReferenceRun
    results: list[MethodResult]
    extras: dict[str, list[ReportExtra]] = field(default_factory=dict)
    ssaa: int = 1
    references: dict[str, ReferenceRun] = field(default_factory=dict)
    untraced: dict[str, ReferenceRun] = field(default_factory=dict)

    @property
    def reliable(self) -> bool:
        """Whether every method's metrics can be trusted (:func:`reliable_against`)."""
        return all(result.reliable for result in self.results)

    @property
    def unreliable_reason(self) -> str | None:
        """Why the marked methods' metrics cannot be trusted, or None when all are reliable.

        One reason per reference that left a method unreliable, named by its model when
        there are several, in the order of the methods; a method whose model no reference
        renders says so. Never None while :attr:`reliable` is false.
        """
        references = self.references or {"": self.reference}
        reasons: dict[str, None] = {}
        for result in self.results:
            if result.reliable:
                continue
            if result.missing_input:
                reasons[f"{result.name}: {result.missing_input}"] = None
                continue
            run = references.get(result.reference_model or "")
            reason = run.unreliable_reason if run is not None else None
            if run is None or reason is None:
                reason = f"{result.name}: no reference of its reflectance model"
            elif len(references) > 1:
                reason = f"reference ({result.reference_model}): {reason}"
            reasons[reason] = None
        return "; ".join(reasons) if reasons else None


def method_classes(names: Sequence[str]) -> list[type[Method]]:
    """The reference's class and those of ``names`` (registered), each once, reference first.

    Raises
    ------
    ParameterError
        If a name is not a registered method.
    """
    truth = ground_truth_class()
    classes: dict[str, type[Method]] = {truth.name: truth}
    for name in names:
        classes.setdefault(name, method_class(name))
    return list(classes.values())


def plan_parameters(classes: Sequence[type[Method]], assignments: Sequence[str]) -> ParameterPlan:
    """Validate ``--param name=value`` strings for a comparison of ``classes``.

    Parameters
    ----------
    classes
        The method classes compared, the reference's included.
    assignments
        ``name=value`` strings.

    Raises
    ------
    ParameterError
        A malformed assignment, a value out of range, or a name that neither a
        method of ``classes`` nor the display declares.
    """
    display_decl = {p.name: p for p in DISPLAY_PARAMETERS}
    plan = ParameterPlan({cls.name: {} for cls in classes}, {})
    for name, value in parse_assignments(assignments).items():
        if name in display_decl:
            plan.display[name] = display_decl[name].validate(value)
            continue
        takers = [(cls, p) for cls in classes for p in cls.parameters if p.name == name]
        if not takers:
            raise ParameterError(
                f"--param {name}: no method of this comparison declares it "
                f"({', '.join(cls.name for cls in classes)}; "
                f"display: {', '.join(display_decl)})"
            )
        for cls, declared in takers:
            plan.methods[cls.name][name] = declared.validate(value)
    return plan


def run_comparison(
    session: RenderSession,
    names: Sequence[str],
    size: tuple[int, int],
    plan: ParameterPlan,
    frames: int = 20,
    warmup: int = 3,
    progress: bool = False,
    cache: bool = False,
    strict: bool = False,
    time_limit_s: float | None = None,
    extras_dir: Path | None = None,
    ssaa: int = 1,
    decompose: bool = True,
    reference_kind: str = EXACT,
    lobes: LobeEvaluator | None = None,
) -> Comparison:
    """Render ``names`` and the reference at the session's camera and compare them.

    Parameters
    ----------
    session
        The session, camera already placed; its methods get ``plan``'s values.
    names
        Registered method names (``reference`` compares the reference with itself).
    size
        Width, height in pixels, each ≥ core.metrics.MIN_SIZE.
    plan
        From :func:`plan_parameters` for the reference and ``names``.
    frames, warmup
        Timed and untimed frames per method.
    progress
        Show a progress line on stderr while the reference accumulates.
    cache
        Resume the reference from, and save it to, measure/ground_truth_cache.py; read an
        exact frame evaluated before from, and keep a new one in, measure/exact_cache.py.
    strict
        Stop the reference by its tolerance, not by the methods' errors
        (measure/stopping.py; an explicit ``tolerance`` in ``plan`` does too).
    time_limit_s
        The reference's time limit in seconds (its ``time_limit``; None keeps ``plan``'s).
    extras_dir
        The report's folder (made if missing): each compared method's
        :meth:`Method.report_extras` runs after the measurements and writes its
        images there. None: no extras.
    ssaa
        Render each method at ``ssaa`` × ``ssaa`` samples per pixel and box-filter
        them, as the reference averages each pixel's footprint (1: the pixel centre).
        Its time per frame is still taken at one sample per pixel, as a user's frame.
    decompose
        Where the reference traces (ground_truth.SCENE_EFFECTS), also accumulate it
        untraced and report each method's approximation error against that, its
        scene error against the traced one, and the scene-only share between them.
    reference_kind
        :data:`EXACT`: a model with an exact untraced evaluation
        (exact_reference.EXACT_MODELS) is evaluated exactly, at the methods' ``ssaa``
        samples, wherever the untraced model is wanted: as the reference itself when it does
        not trace, as the approximation column's when it does (the traced one stays Monte
        Carlo); another model is Monte Carlo with a one-line note. :data:`MONTE_CARLO`:
        Monte Carlo throughout.
    lobes
        The GPU evaluation of the glossy lobes the exact references use, kept by the caller
        with its environment's pyramid from one comparison to the next (None: one made and
        freed per reference).

    Raises
    ------
    ParameterError
        If the camera sees no reflector (empty mask).
    """
    for name, value in plan.display.items():
        session.renderer.display[name] = value
    truth_class = ground_truth_class()
    truth = truth_class.name
    reference = session.method(truth)
    reference.values.update(plan.methods[truth])
    if time_limit_s is not None:
        reference.values["time_limit"] = time_limit_s
    groups = reflectance_groups(names, str(reference.values["model"]))
    if strict and len(groups) > 1:
        raise ParameterError(
            f"--strict: these methods need {len(groups)} references ("
            + "; ".join(f"{model}: {', '.join(members)}" for model, members in groups.items())
            + "); compare them one model at a time to stop each by its tolerance"
        )
    rendered = {
        name: _render_method(session, name, plan.methods[name], reference, size, ssaa)
        for name in names
        if name != truth
    }
    rule = choose_rule(list(names), plan.methods[truth], strict)
    base = dict(reference.values.as_dict())
    runs: dict[str, ReferenceRun] = {}
    untraced: dict[str, ReferenceRun] = {}
    masks: dict[str, npt.NDArray[np.bool_]] = {}  # each reference's coverage: its methods'
    for model, members in groups.items():
        reference.values.update(base)
        reference.values.update(_reference_values(session, reference, model, members, base))
        traces = reference.traces_anything()
        # tracing asked for but changing nothing: the untraced reference is the traced one
        untraced_is_traced = decompose and not traces and bool(base.get(SCENE_EFFECTS))
        exact = reference_kind == EXACT and model in EXACT_MODELS
        if reference_kind == EXACT and not exact:
            print(
                f"envstudio: note: reference model {model} has no exact evaluation yet: "
                "Monte Carlo",
                file=sys.stderr,
            )
        background = next((rendered[n][2] for n in members if n in rendered), None)
        if exact and not traces:  # the untraced model is the reference: nothing to sample
            runs[model], masks[model] = exact_run(
                session, reference, size, ssaa, background, cache, lobes
            )
            if untraced_is_traced:
                untraced[model] = _as_untraced(runs[model])
            continue
        judge = ReferenceJudge(rule, {name: rendered[name][2] for name in members})
        if exact and traces:  # a control variate: traced = exact untraced + sampled difference
            known, known_mask = exact_run(session, reference, size, ssaa, background, cache, lobes)
            reference.values[UNTRACED_TOO] = True
            runs[model], masks[model] = converge(
                session, reference, size, progress, False, judge, control=(known.hdr, known_mask)
            )
            runs[model] = replace(runs[model], exact_error=known.exact_error)
            if decompose:
                untraced[model] = replace(known, parameters=_as_untraced(runs[model]).parameters)
            continue
        shared = decompose and traces
        if shared:  # the untraced estimate from the same samples
            reference.values[UNTRACED_TOO] = True
        runs[model], masks[model] = converge(session, reference, size, progress, cache, judge)
        if shared:
            untraced[model] = untraced_run(session, reference, runs[model], masks[model])
        elif untraced_is_traced:
            untraced[model] = _as_untraced(runs[model])
    first = next(iter(runs))
    model_of = {name: model for model, members in groups.items() for name in members}
    model_of[truth] = first
    ref_run = runs[first]
    frames_of = {
        name: rendered.get(name, (reference, None, ref_run.hdr, ref_run.display)) for name in names
    }
    timings = _time_methods(session, list(rendered), size, frames, warmup)
    timings[truth] = (
        _summary(ref_run.frames_ms),
        "median of its accumulation frames",
    )
    results = []
    for name, (method, glossiness, hdr, display) in frames_of.items():
        own = runs.get(model_of.get(name, ""))
        mask = masks.get(model_of.get(name, ""), masks[first])
        result = MethodResult(
            name=name,
            parameters=method.values.as_dict(),
            matched={n: method.values[n] for n in MATCHED_NAMES if n in method.values},
            glossiness=glossiness,
            metrics=compare_images(display, (own or ref_run).display, mask),
            relative_error=relative_error(hdr, (own or ref_run).hdr),
            frame_ms=timings[name][0],
            timing=timings[name][1],
            hdr=hdr,
            display=display,
            reference_model=model_of.get(name),
        )
        if own is None:
            results.append(_without_truth(result))
            continue
        results.append(_judge(result, own, mask, truth))
        result.missing_input = method.missing_input()
        if result.missing_input:  # a stand-in's numbers are not the method's
            _without_truth(result)
            continue
        approximation = untraced.get(model_of[name])
        if approximation is not None:
            result.approximation = compare_images(display, approximation.display, mask)
            result.approximation_error = median_error(hdr, approximation.hdr, mask)
            result.scene_only_error = median_error(approximation.hdr, own.hdr, mask)
    extras = _report_extras(session, list(rendered), extras_dir)
    camera = session.camera
    return Comparison(
        scene=session.scene.label,
        size=tuple(size),
        camera=(camera.azimuth, camera.elevation, camera.distance),
        display=session.renderer.display.as_dict(),
        device=describe(session.ctx),
        mask=masks[first],
        reference=ref_run,
        results=results,
        extras=extras,
        ssaa=ssaa,
        references=runs,
        untraced=untraced,
    )


def _as_untraced(run: ReferenceRun) -> ReferenceRun:
    """``run`` under the untraced reference's parameters (scene effects off)."""
    return replace(run, parameters=run.parameters | {SCENE_EFFECTS: False, UNTRACED_TOO: False})


def reflectance_groups(names: Sequence[str], base_model: str) -> dict[str, list[str]]:
    """Model → the methods of ``names`` that render it and that the ground truth can render.

    The ground truth's own model (``base_model``: the scene's, or ``--param model``) comes
    first; a comparison of the ground truth alone is that model's group, empty.
    """
    truth = ground_truth_class()
    groups: dict[str, list[str]] = {base_model: []}
    for name in names:
        cls = method_class(name)
        if name != truth.name and cls.reflectance in truth.models:
            groups.setdefault(cls.reflectance, []).append(name)
    if not groups[base_model] and len(groups) > 1 and truth.name not in names:
        del groups[base_model]
    return groups


def _reference_values(
    session: RenderSession, reference: Method, model: str, members: list[str], base: dict
) -> dict[str, object]:
    """The ground truth's values for ``model``: the model, and for a model other than its own
    the material parameters it shares with the group's first method (its paper's material)."""
    values: dict[str, object] = {"model": model}
    if not members:
        return values
    method = session.method(members[0])
    if "roughness" in method.values and "phong_exponent" in reference.values:
        match_roughness(reference, method)  # the group's GGX alpha as the reference's N
        values["phong_exponent"] = reference.values["phong_exponent"]
    if model == base["model"]:
        return values
    shared = [p.name for p in method.values if p.name in reference.values and p.name != "model"]
    return values | {name: method.values[name] for name in shared}


def _without_truth(result: MethodResult) -> MethodResult:
    """No numbers: the ground truth cannot render the method's model, or its input is missing."""
    nan = float("nan")
    result.metrics = ImageMetrics(nan, nan, nan, np.zeros_like(result.metrics.flip_map))
    result.median_relative_error = nan
    result.relative_error = np.zeros_like(result.relative_error)
    result.reliable = False
    return result


def _report_extras(
    session: RenderSession, names: list[str], out_dir: Path | None
) -> dict[str, list[ReportExtra]]:
    """Method name → its report sections (those that add some), images written to ``out_dir``."""
    if out_dir is None:
        return {}
    out_dir = Path(out_dir)
    out_dir.mkdir(exist_ok=True)
    extras = {name: session.method(name).report_extras(session, out_dir) for name in names}
    return {name: sections for name, sections in extras.items() if sections}


def _render_method(
    session: RenderSession,
    name: str,
    values: dict[str, object],
    reference: GroundTruth,
    size: tuple[int, int],
    ssaa: int = 1,
) -> tuple[Method, str | None, npt.NDArray[np.float32], npt.NDArray[np.float32]]:
    """Render method ``name`` with ``values`` until finished, glossiness matched to ``reference``.

    With ``ssaa`` > 1 the frame is rendered at ``ssaa`` times the size and filtered in
    linear radiance over each pixel's footprint as the reference is (:func:`footprint_filter`).

    Returns
    -------
    tuple
        The method, how its ``lod_bias`` was matched (or None), its linear HDR
        frame (h, w, 3) and its display image.
    """
    method = session.method(name)
    method.values.update(values)
    glossiness = None
    if "lod_bias" not in values and "roughness" not in values:
        glossiness = match_glossiness(method, reference, session.gpu_scene.cube_size)
    fine = (size[0] * ssaa, size[1] * ssaa)
    session.render_offscreen(method, fine)
    while not method.finished():
        session.render_offscreen(method, fine)
    hdr = session.read_hdr()
    if ssaa > 1:
        covered = session.renderer.reflector_coverage(session.gpu_scene, session.camera, fine)
        hdr = footprint_filter(hdr, covered, ssaa)
    return method, glossiness, hdr, display_image(session, hdr)


def footprint_filter(
    image: npt.NDArray[np.float32], covered: npt.NDArray[np.bool_], factor: int
) -> npt.NDArray[np.float32]:
    """(h·factor, w·factor, 3) samples → (h, w, 3) pixels, as the reference filters a footprint.

    A pixel that a reflector covers in part is the mean of its samples on the reflector
    (the reference drops the footprint samples that miss the reflectors); one it does not
    cover is the mean of all its samples.

    Parameters
    ----------
    image : (h·factor, w·factor, 3) float32
        Linear radiance, one sample per fine pixel.
    covered : (h·factor, w·factor) bool
        Samples on a reflector.
    factor : int
        Samples per pixel along each axis.
    """
    if factor == 1:
        return image
    h, w = image.shape[0] // factor, image.shape[1] // factor
    blocks = image.reshape(h, factor, w, factor, -1).astype(np.float64)
    weights = covered.reshape(h, factor, w, factor, 1).astype(np.float64)
    count = weights.sum(axis=(1, 3))
    on = (blocks * weights).sum(axis=(1, 3)) / np.maximum(count, 1.0)
    return np.where(count > 0, on, blocks.mean(axis=(1, 3))).astype(np.float32)


def _judge(
    result: MethodResult, reference: ReferenceRun, mask: npt.NDArray[np.bool_], truth: str
) -> MethodResult:
    """Set the method's median relative error and whether its metrics can be trusted.

    Trusted when the reference converged, or when the reference's own noise
    (its median relative standard error) is below :data:`NOISE_SHARE` of the
    method's median relative error over the mask: the measured difference is
    then the method's, not the reference's noise. The reference compared with
    itself is exact. A control-variate reference, whose noise is known per pixel, is
    judged by the uncertainty that noise leaves in the method's median error instead
    (stopping.control_variate_uncertainty), and by its exact part's checked error. The same
    test as the noise rule's (measure/stopping.py), on the same numbers when the reference
    stopped by it.
    """
    result.median_relative_error = median_error(result.hdr, reference.hdr, mask)
    uncertainty = reference.relative_standard_error
    if reference.pixel_noise is not None:  # the noise left, and the exact part's bound
        uncertainty = control_variate_uncertainty(
            result.hdr, reference.hdr, reference.pixel_noise, mask, reference.half_hdr
        )
        if reference.exact_error is not None:
            uncertainty = max(uncertainty, reference.exact_error.median)
    result.reliable = (
        reference.converged
        or result.name == truth
        or uncertainty < NOISE_SHARE * result.median_relative_error
    )
    return result


def _time_methods(
    session: RenderSession, names: list[str], size: tuple[int, int], frames: int, warmup: int
) -> dict[str, tuple[dict[str, float], str]]:
    """Method name → (median/p95 ms per frame, how it was measured), by the bench code path."""
    if not names:
        return {}
    report = run_bench(session, names, size, frames, warmup, progress=False)
    how = f"bench: median of {frames} frames after {warmup} warm-up"
    return {name: (report["methods"][name]["frame"], how) for name in names}


def _summary(samples: list[float]) -> dict[str, float]:
    values = np.asarray(samples, dtype=np.float64)
    return {"median_ms": float(np.median(values)), "p95_ms": float(np.percentile(values, 95))}
