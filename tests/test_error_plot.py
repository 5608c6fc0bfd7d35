"""The viewer's error-against-glossiness plot (issue 40 item 5): its background measurement
(ui/error_plot.py's GlossinessCurve, measure/curve_job.py's child process) without a window."""

from __future__ import annotations

import math
import multiprocessing
import os
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import envstudio as es
from envstudio.engine.session import RenderSession
from envstudio.measure.error_curve import ErrorCurve
from envstudio.ui.error_plot import (
    STILL_S,
    GlossinessCurve,
    current_exponent,
    duration,
    nearest_curve,
)
from test_reference_cache import _gradient
from test_render_gl import sphere_scene

SIZE, SSAA = (32, 32), 2
EXPONENTS = (20.0, 50.0)
METHODS = ["mirror", "splitsum", "banks"]
WAIT_S = 60.0
"""At most this long for a measurement (about 3 s here)."""


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


@pytest.fixture
def clock():
    return Clock()


@pytest.fixture
def plot(clock):
    """The plot at :data:`EXPONENTS` and :data:`SIZE`, on ``clock``; released after the test
    (its child ended) however the test ended."""
    curve = GlossinessCurve(EXPONENTS, SIZE, SSAA, clock)
    yield curve
    curve.release()


def _started(plot: GlossinessCurve, session: RenderSession, clock: Clock) -> None:
    """A frame after the view has been still long enough: the measurement starts."""
    clock.now += STILL_S
    plot.update(session)
    assert plot.measuring


def _frames_until(done, plot: GlossinessCurve, session: RenderSession) -> list[str]:
    """Frames (the view unchanged) until ``done()``; returns the progress each showed."""
    shown, deadline = [], time.monotonic() + WAIT_S
    while not done():
        assert time.monotonic() < deadline, f"nothing after {WAIT_S} s: {plot.progress()}"
        time.sleep(0.02)
        plot.update(session)
        shown.append(plot.progress())
    return shown


def _snapshots() -> set[Path]:
    return set(Path(tempfile.gettempdir()).glob("envstudio-curve-*.pickle"))


def test_the_background_points_are_error_curves_and_a_change_of_view_restarts_them(
    viewer, plot, clock
):
    """Splitsum (GGX alpha matched to N) and mirror, measured in the child while this
    process measures the same view with es.error_curve: the same numbers. Moving the camera
    ends the running child and starts another for the new view."""
    plot.update(viewer)  # the first frame notices the view
    plot.start(METHODS)
    plot.update(viewer)  # not still long enough yet
    assert not plot.measuring and plot.progress() == "0 of 2, waiting for a still view"
    _started(plot, viewer, clock)
    first = [child.pid for child in multiprocessing.active_children()]
    assert len(first) == 1

    viewer.camera.azimuth += 30.0
    plot.update(viewer)
    assert plot.running and not plot.measuring and plot.done == 0 and plot.curve is None
    assert multiprocessing.active_children() == [], "the first child still runs"
    _started(plot, viewer, clock)
    second = [child.pid for child in multiprocessing.active_children()]
    assert len(second) == 1 and second != first

    camera = viewer.camera
    expected = es.error_curve(
        viewer.scene,
        METHODS,
        EXPONENTS,
        SIZE,
        SSAA,
        camera=(camera.azimuth, camera.elevation, camera.distance),
    )
    shown = _frames_until(lambda: not plot.running, plot, viewer)
    assert plot.error is None and not plot.measuring and plot.progress() == ""
    # the first point came while the second was measured, with the time left
    assert any(p.startswith("1 of 2, ") and p.endswith(" s left") for p in shown), shown
    assert plot.curve.notes == expected["notes"]
    assert sorted(plot.curve.errors) == sorted(expected["methods"]) == ["mirror", "splitsum"]
    assert plot.curve.exponents == list(EXPONENTS)
    for name, numbers in expected["methods"].items():
        np.testing.assert_allclose(
            plot.curve.errors[name], numbers["median_relative_error"], rtol=1e-6
        )
        np.testing.assert_allclose(plot.curve.psnr_db[name], numbers["psnr_db"], rtol=1e-6)
    assert multiprocessing.active_children() == []

    camera.azimuth += 10.0  # the finished curve is kept, marked as for another view
    measured = plot.curve
    plot.update(viewer)
    assert plot.stale and plot.curve is measured and not plot.running


def test_release_while_measuring_ends_the_child_at_once_and_leaves_nothing_behind(
    viewer, plot, clock
):
    threads, snapshots = threading.enumerate(), _snapshots()
    plot.update(viewer)
    plot.start(["splitsum"])
    _started(plot, viewer, clock)
    (child,) = multiprocessing.active_children()
    pid = child.pid
    _frames_until(lambda: plot.curve is not None, plot, viewer)  # its session made: measuring
    assert plot.running and plot.done == 0

    started = time.perf_counter()
    plot.release()
    assert time.perf_counter() - started < 1.0
    assert not plot.running and not plot.measuring
    assert multiprocessing.active_children() == []
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)
    assert threading.enumerate() == threads
    assert _snapshots() <= snapshots, "the scene's copy was left in the temporary folder"
    plot.release()


def test_a_measurement_that_cannot_run_says_why_on_one_line(viewer, plot, clock):
    plot.update(viewer)
    plot.start(["banks"])  # no exact reference along N: the child's reason, nothing running
    _started(plot, viewer, clock)
    _frames_until(lambda: not plot.running, plot, viewer)
    assert plot.error is not None and "none has an exact reference" in plot.error
    assert "\n" not in plot.error
    assert multiprocessing.active_children() == []


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


def test_the_time_left_reads_in_seconds_then_minutes():
    assert duration(0.2) == "0 s"
    assert duration(40.4) == "40 s"
    assert duration(125.0) == "2 min 05 s"


def test_the_marked_exponent_is_the_shown_methods_else_the_ground_truths(viewer):
    hwconv, mirror = viewer.method("hwconv"), viewer.method("mirror")
    hwconv.values["phong_exponent"] = 300.0
    assert current_exponent(hwconv, None) == 300.0
    assert current_exponent(mirror, hwconv) == 300.0
    assert current_exponent(mirror, None) is None
