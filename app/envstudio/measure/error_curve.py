"""Each method's approximation error across glossiness: the error-against-N curve (issue 40,
items 5 and 6).

For each Phong exponent N, :func:`error_curve` runs ``compare``'s own comparison
(:func:`envstudio.measure.compare.run_comparison`) with the exact untraced reference
(``reference_kind=exact``, the reference's ``trace=false``, measure/exact_reference.py) at
that N: every method declaring ``phong_exponent`` takes N, a mip method's LOD bias is
matched to it as compare matches it (a GGX ``roughness`` too, once its model, microfacet,
has an exact reference). The numbers are compare's:
the median relative luminance error over the reflector and PSNR of the display images, so a
point of the curve is the row ``compare --reference exact --param trace=false --param
phong_exponent=N`` reports. One session renders every N.

Methods of a model the Phong exponent does not set (banks: :data:`CURVE_MODELS`) and of a
model with no exact evaluation (a plugin's own, exact_reference.EXACT_MODELS) are left out
with a note.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from envstudio.engine.registry import method_class
from envstudio.engine.session import RenderSession
from envstudio.errors import ParameterError, UserError
from envstudio.measure.compare import method_classes, plan_parameters, run_comparison
from envstudio.measure.exact_reference import EXACT_MODELS
from envstudio.measure.reference_runs import EXACT

#: The reflectance models a Phong exponent sets (microfacet by GGX α = √(2 / (4N + 2))): the
#: curve's axis; the other exact models (banks) have no point on it.
CURVE_MODELS = ("phong", "microfacet")
NO_EXPONENT = "has no Phong exponent (its lobe's width is its sharpness)"


@dataclass
class ErrorCurve:
    """Each method's approximation error at each Phong exponent.

    Attributes
    ----------
    exponents : list of float
        The Phong exponents N, in the order measured.
    errors : dict of str to list of float
        Method → its median relative luminance error at each N (compare's
        ``median_relative_error``; NaN where it has no numbers, e.g. pem without a bake).
    psnr_db : dict of str to list of float
        Method → its PSNR (dB) at each N, on the display images over the reflector.
    notes : list of str
        One line per method left out, and why.
    """

    exponents: list[float]
    errors: dict[str, list[float]] = field(default_factory=dict)
    psnr_db: dict[str, list[float]] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        """``{"exponents": [...], "methods": {name: {"median_relative_error": [...],
        "psnr_db": [...]}}}``, with ``"notes"`` when a method was left out."""
        out: dict = {
            "exponents": list(self.exponents),
            "methods": {
                name: {"median_relative_error": list(errors), "psnr_db": list(self.psnr_db[name])}
                for name, errors in self.errors.items()
            },
        }
        if self.notes:
            out["notes"] = list(self.notes)
        return out


def curve_methods(names: Sequence[str]) -> tuple[list[str], list[str]]:
    """``names`` split into those with an exact reference and notes on the others.

    Returns
    -------
    kept : list of str
        The methods of a reflectance model in :data:`CURVE_MODELS`, in order.
    notes : list of str
        "banks: reflectance model banks has no Phong exponent (its lobe's width is its
        sharpness)", one per method left out.
    """
    kept, notes = [], []
    for name in names:
        model = method_class(name).reflectance
        if model in CURVE_MODELS:
            kept.append(name)
        elif model in EXACT_MODELS:
            notes.append(f"{name}: reflectance model {model} {NO_EXPONENT}")
        else:
            notes.append(f"{name}: reflectance model {model} has no exact reference yet")
    return kept, notes


def check_exponents(value: object, names: Sequence[str]) -> tuple[float, ...]:
    """Phong exponents every compared method that declares ``phong_exponent`` accepts.

    Parameters
    ----------
    value
        As the caller passed it: a non-empty sequence of finite positive numbers.
    names
        The methods compared (the reference is added).

    Raises
    ------
    ParameterError
        Anything else, or an N outside a declaring method's range (named).
    """
    shown = f"{value!r}"[:80]
    items = list(value) if isinstance(value, (list, tuple)) else []
    if not items or not all(
        isinstance(n, (int, float)) and not isinstance(n, bool) and math.isfinite(n) for n in items
    ):
        raise ParameterError(f"exponents {shown}: expected a list of Phong exponents (numbers)")
    for cls in method_classes(list(names)):
        declared = next((p for p in cls.parameters if p.name == "phong_exponent"), None)
        if declared is None:
            continue
        outside = [n for n in items if not declared.minimum <= n <= declared.maximum]
        if outside:
            raise ParameterError(
                f"exponents {shown}: {outside[0]!r} is outside {cls.name}'s phong_exponent "
                f"range {declared.minimum:g}..{declared.maximum:g}"
            )
    return tuple(float(n) for n in items)


def error_curve(
    session: RenderSession,
    names: Sequence[str],
    exponents: Sequence[float],
    size: tuple[int, int],
    ssaa: int,
    parameters: Sequence[str] = (),
    progress: Callable[[int, int], None] | None = None,
) -> ErrorCurve:
    """Every method's approximation error at each of ``exponents``, in ``session``.

    Parameters
    ----------
    session
        The session, its camera placed.
    names
        Registered method names (checked); those without an exact reference are left out
        with a note (:func:`curve_methods`).
    exponents
        Phong exponents N (:func:`check_exponents`).
    size
        Width, height in pixels, each at least core.metrics.MIN_SIZE.
    ssaa
        Footprint samples per pixel per axis (compare's ``--ssaa``).
    parameters
        ``name=value`` assignments for every method declaring ``name`` (compare's
        ``--param``), besides the reference's ``trace`` and every ``phong_exponent``.
    progress
        Called with (points done, points in all) after each N.

    Raises
    ------
    ParameterError
        If the camera sees no reflector, or no method has an exact reference. A method
        that refuses its values at some N (hwconv's ``border`` at a small N) gets NaN
        there and a note instead.
    """
    steps = CurveSteps(session, names, exponents, size, ssaa, parameters)
    while not steps.finished:
        steps.step()
        if progress is not None:
            progress(steps.done, steps.total)
    return steps.curve


class CurveSteps:
    """:func:`error_curve` one exponent at a time (the viewer's background measurement,
    measure/curve_job.py, sends the points after each): after :attr:`total` calls of
    :meth:`step`, :attr:`curve` holds what :func:`error_curve` returns for the same arguments.

    Parameters
    ----------
    session, names, exponents, size, ssaa, parameters
        As :func:`error_curve`'s; the camera is read at each step.

    Raises
    ------
    ParameterError
        As :func:`error_curve`: no method with an exact reference, or a camera that sees no
        reflector.
    """

    def __init__(
        self,
        session: RenderSession,
        names: Sequence[str],
        exponents: Sequence[float],
        size: tuple[int, int],
        ssaa: int,
        parameters: Sequence[str] = (),
    ):
        kept, notes = curve_methods(names)
        if not kept:
            raise ParameterError(
                f"methods {list(names)!r}: none has an exact reference along N ({'; '.join(notes)})"
            )
        _check_view(session, size, ssaa)
        self.session = session
        self.names = kept
        self.size, self.ssaa, self.parameters = size, ssaa, list(parameters)
        self.curve = ErrorCurve(
            list(exponents), {n: [] for n in kept}, {n: [] for n in kept}, notes
        )
        self.done = 0
        """Exponents measured so far."""

    @property
    def total(self) -> int:
        """Exponents in all."""
        return len(self.curve.exponents)

    @property
    def finished(self) -> bool:
        """Whether every exponent is measured."""
        return self.done >= self.total

    def step(self) -> None:
        """Measure the next exponent (nothing once finished)."""
        if self.finished:
            return
        exponent = self.curve.exponents[self.done]
        assignments = [*self.parameters, "trace=false", f"phong_exponent={exponent!r}"]
        measured = _measured(self.session, self.names, self.size, self.ssaa, assignments)
        for name, found in measured.items():
            if isinstance(found, str):
                self.curve.notes.append(f"{name} at N = {exponent:g}: {found}")
                found = (math.nan, math.nan)
            self.curve.errors[name].append(found[0])
            self.curve.psnr_db[name].append(found[1])
        self.done += 1


def _measured(
    session: RenderSession,
    names: list[str],
    size: tuple[int, int],
    ssaa: int,
    assignments: list[str],
) -> dict[str, tuple[float, float] | str]:
    """Method → (median relative error, PSNR) of one comparison of ``names``, or the first
    line of the error that kept it from rendering (a value its method refuses at this N,
    such as hwconv's border at a small N): then each method alone, so the others keep
    their numbers."""
    plan = plan_parameters(method_classes(names), assignments)
    try:
        comparison = run_comparison(
            session, names, size, plan, frames=1, warmup=0, ssaa=ssaa, reference_kind=EXACT
        )
    except UserError as exc:
        if len(names) == 1:
            return {names[0]: str(exc).splitlines()[0]}
        return {
            name: found
            for name in names
            for found in _measured(session, [name], size, ssaa, assignments).values()
        }
    return {r.name: (r.median_relative_error, r.metrics.psnr_db) for r in comparison.results}


def _check_view(session: RenderSession, size: tuple[int, int], ssaa: int) -> None:
    """Raise ParameterError, as compare does, when the camera sees no reflector."""
    fine = (size[0] * ssaa, size[1] * ssaa)
    if not session.renderer.reflector_coverage(session.gpu_scene, session.camera, fine).any():
        camera = session.camera
        raise ParameterError(
            f"camera at azimuth {camera.azimuth:g}°, elevation {camera.elevation:g}°, "
            f"distance {camera.distance:g} sees no reflector (empty mask): no error to measure"
        )
