"""The Compare panel's error-against-glossiness plot (issue 40 item 5).

"Measure glossiness curve" measures, for the scene and camera on show, each method's
approximation error against the exact untraced reference at :data:`EXPONENTS` (the
Phong exponent N, 5 to 5000), as ``es.error_curve`` does (measure/error_curve.py): one
exponent a frame (:class:`GlossinessCurve`), each step taken once the view has stayed
unchanged for :data:`STILL_S`. A step renders every method and the exact reference at
:data:`SIZE` (about two seconds on a software rasteriser): the window pauses for that
long, then draws a frame with the progress ("3 of 10"). Moving the camera or changing
the scene starts the points again for the new view; a finished curve stays shown,
marked as measured for an earlier view.

The measurement runs in a session of its own sharing the window's context (the curve
sets each method's N and the display's defaults; the window's methods keep their
values), with a copy of the camera taken when the points start.

The plot (ImPlot, log–log): each method's median relative error against N, the current
N (the method on show's, else the ground truth's, which the matching goes through) as a
vertical line. Clicking near a curve, or on its legend entry, selects that method.
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable, Sequence

import numpy as np
from imgui_bundle import imgui, implot

from envstudio.engine.method import Method
from envstudio.engine.session import RenderSession
from envstudio.errors import UserError
from envstudio.measure.error_curve import CurveSteps, ErrorCurve

EXPONENTS = (5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0, 5000.0)
"""The Phong exponents N measured, as es.error_curve's default."""
#: The models the window's curve measures: Phong's exact reference takes a fraction of a
#: second a point; the microfacet one's GPU descent takes seconds on a software renderer, too
#: long between two frames (es.error_curve measures it).
WINDOW_MODELS = ("phong",)
SIZE = (64, 64)
#: Both axes reach this factor past the first and last values (their markers whole).
MARGIN = 1.3
SSAA = 2
STILL_S = 0.3
"""Seconds the view must stay unchanged before a step is taken."""
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


class GlossinessCurve:
    """The points of the error-against-N curve, measured a step at a time.

    Parameters
    ----------
    exponents, size, ssaa
        As :func:`envstudio.measure.error_curve.error_curve`'s.
    clock
        Seconds, monotonic (:func:`time.monotonic`).
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
        self._steps: CurveSteps | None = None
        self._session: RenderSession | None = None
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
    def done(self) -> int:
        """Exponents measured for the current view."""
        return self._steps.done if self._steps is not None else 0

    @property
    def total(self) -> int:
        """Exponents in all."""
        return len(self.exponents)

    def progress(self) -> str:
        """The progress, "3 of 10", while running; "" otherwise."""
        return f"{self.done} of {self.total}" if self.running else ""

    def start(self, names: Sequence[str]) -> None:
        """Measure ``names`` (those without an exact reference are left out with a note)
        from the next still frame on."""
        self._drop_steps()
        self._wanted = list(names)
        self.error = None

    def stop(self) -> None:
        """Stop measuring; the points so far stay in :attr:`curve`."""
        self._wanted = None
        self._drop_steps(keep_curve=True)

    def update(self, session: RenderSession) -> bool:
        """Call every frame before drawing: notice a change of view, and take a step when one
        is due. Returns whether a step was taken."""
        now, view = self._clock(), view_key(session)
        if view != self._view:
            self._view, self._still_since = view, now
            if self.curve is not None and not self.running:
                self.stale = True
            if self._steps is not None:  # the points so far were for another view
                self._drop_steps()
            return False
        if not self.running or now - self._still_since < STILL_S:
            return False
        if self._steps is None:
            try:
                self._begin(session)
            except UserError as exc:
                self.error = str(exc).splitlines()[0]
                self.stop()
                return False
        try:
            self._steps.step()
        except UserError as exc:
            self.error = str(exc).splitlines()[0]
            self.stop()
            return True
        if self._steps.finished:
            self._wanted = None
            self._drop_steps(keep_curve=True)
        return True

    def _begin(self, session: RenderSession) -> None:
        own = RenderSession(session.scene, ctx=session.ctx, cube_size=session.gpu_scene.cube_size)
        own.camera = copy.deepcopy(session.camera)
        try:
            self._steps = CurveSteps(
                own, self._wanted, self.exponents, self.size, self.ssaa, models=WINDOW_MODELS
            )
        except BaseException:
            own.release()
            raise
        self._session = own
        self.curve, self.stale = self._steps.curve, False

    def _drop_steps(self, keep_curve: bool = False) -> None:
        if self._steps is not None and not keep_curve:
            self.curve = None
        self._steps = None
        if self._session is not None:
            self._session.release()
            self._session = None

    def release(self) -> None:
        """Free the measuring session; safe twice."""
        self._wanted = None
        self._drop_steps(keep_curve=True)


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
        f"N = {', '.join(f'{n:g}' for n in plot.exponents)}, for this scene and camera "
        f"({plot.size[0]}x{plot.size[1]}, {plot.ssaa}x{plot.ssaa} samples a pixel), one N "
        "a frame while the view is still. Click a curve to show its method."
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
        implot.setup_legend(implot.Location_.south_west, implot.LegendFlags_.no_buttons)
        for name in curve.errors:
            xs, ys = measured_points(curve, name)
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
