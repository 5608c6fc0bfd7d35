"""The viewer's error-against-glossiness plot (issue 40 item 5): its stepwise measurement
(ui/error_plot.py's GlossinessCurve, measure/error_curve.py's CurveSteps) without a window."""

from __future__ import annotations

import math

import pytest

from envstudio.engine.session import RenderSession
from envstudio.measure.error_curve import ErrorCurve, error_curve
from envstudio.ui.error_plot import STILL_S, GlossinessCurve, current_exponent, nearest_curve
from test_reference_cache import _gradient
from test_render_gl import sphere_scene

SIZE, SSAA = (32, 32), 2
EXPONENTS = (20.0, 2000.0)
METHODS = ["mirror", "hwconv", "banks"]


class Clock:
    def __init__(self):
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def viewer(gl_ctx):
    """The window's session stand-in: a sphere under a small map, in the test's context."""
    session = RenderSession(sphere_scene(_gradient(), rings=16), ctx=gl_ctx)
    yield session
    session.release()


def _still_frames(plot: GlossinessCurve, session: RenderSession, clock: Clock, frames: int):
    """``frames`` frames, each after the view has been still long enough; returns the steps."""
    taken = 0
    for _ in range(frames):
        clock.now += STILL_S
        taken += plot.update(session)
    return taken


def test_the_steps_give_error_curves_numbers_and_count_progress(viewer):
    clock = Clock()
    plot = GlossinessCurve(EXPONENTS, SIZE, SSAA, clock)
    plot.update(viewer)  # the first frame notices the view
    plot.start(METHODS)
    assert plot.running and plot.progress() == "0 of 2"
    assert not plot.update(viewer)  # not still long enough yet
    clock.now += STILL_S
    assert plot.update(viewer)
    assert plot.progress() == "1 of 2"
    assert plot.curve is not None and len(plot.curve.errors["hwconv"]) == 1
    _still_frames(plot, viewer, clock, 3)
    assert not plot.running and plot.progress() == "" and plot.error is None

    # measured in a session of its own: the window's methods keep their values
    assert viewer.method("hwconv").values["phong_exponent"] != EXPONENTS[-1]
    expected = error_curve(viewer, METHODS, EXPONENTS, SIZE, SSAA)
    assert plot.curve.as_dict() == expected.as_dict()
    assert sorted(plot.curve.errors) == ["hwconv", "mirror"]
    assert all(0.0 < e < 1.0 for e in plot.curve.errors["hwconv"])

    viewer.camera.azimuth += 10.0  # the finished curve is kept, marked as for another view
    plot.update(viewer)
    assert plot.stale and plot.curve.as_dict() == expected.as_dict()
    plot.release()
    plot.release()


def test_a_change_of_view_starts_the_points_again_and_errors_are_one_line(viewer):
    clock = Clock()
    plot = GlossinessCurve(EXPONENTS, SIZE, SSAA, clock)
    plot.update(viewer)
    plot.start(["hwconv"])
    assert _still_frames(plot, viewer, clock, 1) == 1 and plot.done == 1
    viewer.camera.azimuth += 30.0
    assert not plot.update(viewer)
    assert plot.running and plot.done == 0 and plot.curve is None
    plot.stop()
    assert not plot.running

    plot.start(["banks"])  # no exact reference: the reason, and nothing running
    _still_frames(plot, viewer, clock, 1)
    assert not plot.running
    assert plot.error is not None and "none has an exact reference" in plot.error
    assert "\n" not in plot.error
    plot.release()


def test_a_click_picks_the_nearest_curve_in_log_error():
    curve = ErrorCurve(
        [10.0, 100.0, 1000.0],
        {"mirror": [0.5, 0.1, 0.01], "hwconv": [0.01, 0.005, math.nan]},
        {"mirror": [0.0] * 3, "hwconv": [0.0] * 3},
    )
    assert nearest_curve(curve, 100.0, 0.12) == "mirror"
    assert nearest_curve(curve, 30.0, 0.008) == "hwconv"
    assert nearest_curve(curve, 100.0, 0.03) is None  # half a decade from both
    assert nearest_curve(curve, 1000.0, 0.005) is None  # hwconv has no point there
    assert nearest_curve(curve, 5000.0, 0.01) is None  # beyond every curve


def test_the_marked_exponent_is_the_shown_methods_else_the_ground_truths(viewer):
    hwconv, mirror = viewer.method("hwconv"), viewer.method("mirror")
    hwconv.values["phong_exponent"] = 300.0
    assert current_exponent(hwconv, None) == 300.0
    assert current_exponent(mirror, hwconv) == 300.0
    assert current_exponent(mirror, None) is None
