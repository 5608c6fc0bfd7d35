"""The Compare panel's error-against-glossiness plot (issue 40 item 5).

"Measure glossiness curve" measures, for the scene and camera on show, each method's
approximation error against the exact untraced reference at :data:`EXPONENTS` (the
Phong exponent N, 5 to 5000; a GGX α matched to each N, α = √(2 / (4N + 2))), as
``es.error_curve`` does (measure/error_curve.py): the Phong methods and the microfacet
one (splitsum); banks, whose lobe no Phong exponent sets, gets a note.

The points are measured in the background, in a child process with its own context
(measure/curve_job.py says why a process): the window draws at its own rate, takes the
points as they arrive and shows the progress ("3 of 10, 40 s left") in a bar. A job starts
once the view has stayed unchanged for :data:`STILL_S`, with a copy of the scene and the
camera; moving the camera or changing the scene stops it and starts the points again for
the new view. A finished curve stays shown, marked as measured for an earlier view.

The plot (ImPlot, log–log): each method's median relative error against N, the current
N (the method on show's, else the ground truth's, which the matching goes through) as a
vertical line. Clicking near a curve, or on its legend entry, selects that method.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence

import numpy as np
from imgui_bundle import imgui, implot

from envstudio.engine.method import Method
from envstudio.engine.session import RenderSession
from envstudio.measure.curve_job import CurveJob
from envstudio.measure.error_curve import ErrorCurve

EXPONENTS = (5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0, 5000.0)
"""The Phong exponents N measured, as es.error_curve's default."""
SIZE = (64, 64)
#: Both axes reach this factor past the first and last values (their markers whole).
MARGIN = 1.3
SSAA = 2
STILL_S = 0.3
"""Seconds the view must stay unchanged before a measurement starts."""
PICK_DECADES = 0.25
"""A click selects the curve nearest in log10 error when it is at most this far."""
PLOT_HEIGHT = 220.0


def view_key(session: RenderSession) -> tuple:
    """What the curve depends on, cheap to compare every frame: the camera, the scene's
    revisions and its nodes' transforms."""
    scene = session.gpu_scene
    camera = session.camera
    return (
        camera.view_matrix().tobytes(),
        camera.fov_y,
        scene.environment_revision,
        scene.geometry_revision,
        tuple(node.transform.matrix().tobytes() for node in session.scene.nodes),
    )


def duration(seconds: float) -> str:
    """``seconds`` as the progress bar says it: "40 s", "2 min 05 s"."""
    whole = round(seconds)
    return f"{whole} s" if whole < 60 else f"{whole // 60} min {whole % 60:02d} s"


class GlossinessCurve:
    """The points of the error-against-N curve, measured in the background.

    Parameters
    ----------
    exponents, size, ssaa
        As :func:`envstudio.measure.error_curve.error_curve`'s.
    clock
        Seconds, monotonic (:func:`time.monotonic`): when the view is still.
    """

    def __init__(
        self,
        exponents: Sequence[float] = EXPONENTS,
        size: tuple[int, int] = SIZE,
        ssaa: int = SSAA,
        clock: Callable[[], float] = time.monotonic,
    ):
        self.exponents = tuple(float(n) for n in exponents)
        self.size, self.ssaa = size, ssaa
        self._clock = clock
        self._wanted: list[str] | None = None
        self._job: CurveJob | None = None
        self._view: tuple | None = None
        self._still_since = 0.0
        self.curve: ErrorCurve | None = None
        """The points measured (all of them once :attr:`running` is False), or None."""
        self.stale = False
        """Whether :attr:`curve` was measured for an earlier view."""
        self.error: str | None = None
        """Why the last measurement could not run (one line), or None."""

    @property
    def running(self) -> bool:
        """Whether points are still to be measured."""
        return self._wanted is not None

    @property
    def measuring(self) -> bool:
        """Whether a child process is measuring now (not waiting for a still view)."""
        return self._job is not None

    @property
    def done(self) -> int:
        """Exponents measured so far by the measurement running now (0 when none runs)."""
        return self._job.done if self._job is not None else 0

    @property
    def total(self) -> int:
        """Exponents in all."""
        return len(self.exponents)

    def progress(self) -> str:
        """The progress while running: "3 of 10, 40 s left" (the time once a point has
        come), "0 of 10, waiting for a still view" before the measurement starts; ""
        otherwise."""
        if not self.running:
            return ""
        counted = f"{self.done} of {self.total}"
        if not self.measuring:
            return f"{counted}, waiting for a still view"
        left = self._job.seconds_left()
        return counted if left is None else f"{counted}, {duration(left)} left"

    def start(self, names: Sequence[str]) -> None:
        """Measure ``names`` (those without an exact reference are left out with a note)
        once the view is still."""
        self._end_job()
        self._wanted = list(names)
        self.error = None

    def stop(self) -> None:
        """Stop measuring; the points so far stay in :attr:`curve`."""
        self._wanted = None
        self._end_job(keep_curve=True)

    def update(self, session: RenderSession) -> None:
        """Call every frame; never waits. Notices a change of view (which stops the
        measurement), starts one once the view is still, and takes the points that came."""
        now, view = self._clock(), view_key(session)
        if view != self._view:
            self._view, self._still_since = view, now
            if self.curve is not None and not self.running:
                self.stale = True
            self._end_job()  # the points so far were for another view
            return
        if self._job is None:
            if self.running and now - self._still_since >= STILL_S:
                self._job = CurveJob(session, self._wanted, self.exponents, self.size, self.ssaa)
                self.curve, self.stale = None, False
            return
        self._job.poll()
        self.curve = self._job.curve
        if self._job.error is not None:
            self.error = self._job.error
            self.stop()
        elif self._job.finished:
            self.stop()

    def _end_job(self, keep_curve: bool = False) -> None:
        if self._job is not None:
            self._job.stop()
            self._job = None
            if not keep_curve:
                self.curve = None

    def release(self) -> None:
        """Stop the measurement, its process ended; safe twice."""
        self.stop()


def measured_points(curve: ErrorCurve, name: str) -> tuple[np.ndarray, np.ndarray]:
    """(N, error) of ``name``'s finite, positive points so far (what a log plot can show)."""
    errors = np.asarray(curve.errors[name], dtype=np.float64)
    exponents = np.asarray(curve.exponents[: len(errors)], dtype=np.float64)
    keep = np.isfinite(errors) & (errors > 0)
    return exponents[keep], errors[keep]


def nearest_curve(curve: ErrorCurve, x: float, y: float) -> str | None:
    """The method whose curve passes nearest (in log10 error, at N = ``x``) to (x, y), if
    within :data:`PICK_DECADES`; None otherwise."""
    if not (x > 0 and y > 0):
        return None
    best, best_distance = None, PICK_DECADES
    for name in curve.errors:
        xs, ys = measured_points(curve, name)
        if len(xs) == 0 or not xs[0] <= x <= xs[-1]:
            continue
        at = np.interp(math.log10(x), np.log10(xs), np.log10(ys))
        distance = abs(at - math.log10(y))
        if distance <= best_distance:
            best, best_distance = name, distance
    return best


def current_exponent(shown: Method, hub: Method | None) -> float | None:
    """The N marked on the plot: the method on show's Phong exponent, else the ground
    truth's (the N the matching goes through); None when neither has one."""
    for method in (shown, hub):
        if method is not None and "phong_exponent" in method.values:
            return float(method.values["phong_exponent"])
    return None


def glossiness_section(
    plot: GlossinessCurve, names: Sequence[str], exponent: float | None
) -> str | None:
    """The Compare panel's plot section; returns the method clicked (a curve or its
    legend entry), or None."""
    imgui.separator()
    if imgui.button("Stop" if plot.running else "Measure glossiness curve"):
        plot.stop() if plot.running else plot.start(names)
    imgui.set_item_tooltip(
        "Each method's median relative error against the exact untraced reference at "
        f"N = {', '.join(f'{n:g}' for n in plot.exponents)} (GGX alpha matched to N), for "
        f"this scene and camera ({plot.size[0]}x{plot.size[1]}, {plot.ssaa}x{plot.ssaa} "
        "samples a pixel), measured in the background once the view is still; moving the "
        "camera starts it again. Click a curve to show its method."
    )
    if plot.running:
        imgui.same_line()
        imgui.progress_bar(plot.done / plot.total, (-1.0, 0.0), plot.progress())
    if plot.error:
        imgui.text_wrapped(plot.error)
    curve = plot.curve
    if curve is None:
        return None
    if plot.stale:
        imgui.text_disabled("measured for an earlier view")
    picked = None
    if implot.begin_plot("##glossiness", (-1.0, PLOT_HEIGHT)):
        implot.setup_axes("Phong exponent N", "median relative error")
        implot.setup_axis_scale(implot.ImAxis_.x1, implot.Scale_.log10)
        implot.setup_axis_scale(implot.ImAxis_.y1, implot.Scale_.log10)
        low, high = min(plot.exponents) / MARGIN, max(plot.exponents) * MARGIN
        implot.setup_axis_limits(implot.ImAxis_.x1, low, high, implot.Cond_.always)
        # the error axis follows the points as they come, none cut at an edge
        ys = np.concatenate([measured_points(curve, name)[1] for name in curve.errors])
        if len(ys):
            low, high = ys.min() / MARGIN, ys.max() * MARGIN
            implot.setup_axis_limits(implot.ImAxis_.y1, low, high, implot.Cond_.always)
        # beside the plot, not over it: a legend of every method covers the low-N points
        implot.setup_legend(
            implot.Location_.north_east,
            implot.LegendFlags_.outside | implot.LegendFlags_.no_buttons,
        )
        for name in curve.errors:
            xs, ys = measured_points(curve, name)
            if not len(xs):  # no point (yet, or none: the notes below say why), no legend entry
                continue
            implot.plot_line(name, xs, ys, implot.Spec(marker=implot.Marker_.circle))
            if implot.is_legend_entry_hovered(name) and imgui.is_mouse_clicked(0):
                picked = name
        if exponent is not None:
            implot.plot_inf_lines("current N", np.array([exponent], dtype=np.float64))
        if picked is None and implot.is_plot_hovered() and imgui.is_mouse_clicked(0):
            mouse = implot.get_plot_mouse_pos()
            picked = nearest_curve(curve, mouse.x, mouse.y)
        implot.end_plot()
    for note in curve.notes:
        imgui.text_wrapped(note)
    return picked
