"""The reference's time budget (``time_limit``) and the noise its status line reports."""

import re
import time

import numpy as np
import pytest
from imgui_bundle import imgui

from envstudio.core.parameters import ParameterValues
from envstudio.engine.session import RenderSession
from envstudio.measure import ground_truth_cache
from envstudio.methods.reference.batch_statistics import median_relative_error
from envstudio.methods.reference.method import SCHEDULING_PARAMETERS, ReferenceMethod
from envstudio.scene.environment import Environment
from envstudio.ui.parameter_widgets import parameter_widgets
from envstudio.ui.status import StatusLine
from test_imgui_gl import draw_frame, gui, imgui_ctx  # noqa: F401 (fixtures)
from test_reference_gl import smooth_environment
from test_render_gl import sphere_scene

SIZE = (32, 32)


def test_a_time_limit_stops_the_reference_and_its_status_line_shows_the_noise(gl_ctx):
    session = RenderSession(sphere_scene(Environment(smooth_environment()), rings=32), ctx=gl_ctx)
    reference = session.method("reference")
    reference.values.update({"trace": False, "tolerance": 1e-5, "samples": 4})
    reference.values["max_samples"] = 10_000_000
    key = ground_truth_cache.cache_path(session, reference, SIZE)
    reference.values["time_limit"] = 0.6
    assert "time_limit" in SCHEDULING_PARAMETERS
    assert ground_truth_cache.cache_path(session, reference, SIZE) == key, "not part of the key"
    start = time.perf_counter()
    session.render_offscreen(reference, SIZE)
    while not reference.finished() and time.perf_counter() - start < 30:
        session.render_offscreen(reference, SIZE)
    status = reference.status
    assert reference.stop_reason() == "time_limit" and not status.converged
    assert 0.6 <= status.run_elapsed() < 0.6 + 6.0  # the limit plus slack for a loaded machine
    line = reference.status_line()
    assert "time limit 0.6 s reached: NOT converged" in line, line
    noise = reference.relative_standard_error()
    assert 0 < noise < 0.5 and status.noise == noise
    shown = float(re.search(r"noise ([0-9.e+-]+) %", line).group(1))
    assert shown == float(f"{100 * noise:.3g}")
    # the noise is the median relative standard error of the estimate
    mask = reference.coverage()
    expected = median_relative_error(reference.estimate(), reference.standard_error(), mask)
    assert noise == expected
    # a larger budget continues the same accumulation (no restart), as in the viewer's field
    batches = status.batches
    reference.values["time_limit"] = 0.0
    assert not reference.finished()
    session.render_offscreen(reference, SIZE)
    assert reference.status.batches == batches + 1
    session.release()


def test_the_noise_is_the_median_over_lit_pixels_of_luminance_error_over_luminance():
    estimate = np.zeros((2, 3, 3), np.float32)
    error = np.zeros_like(estimate)
    estimate[0, :] = [[1.0, 1.0, 1.0], [2.0, 2.0, 2.0], [4.0, 4.0, 4.0]]
    error[0, :] = [[0.1, 0.1, 0.1], [0.1, 0.1, 0.1], [0.1, 0.1, 0.1]]
    mask = np.ones((2, 3), bool)  # the second row is unlit: left out
    assert median_relative_error(estimate, error, mask) == pytest.approx(0.05, rel=1e-6)
    assert median_relative_error(estimate, error, np.zeros_like(mask)) == float("inf")


def test_the_viewer_panel_has_the_time_budget_field(gui):  # noqa: F811 (the fixture)
    """Panels are built from the declarations: the reference's last widget is its time budget."""
    values = ParameterValues(ReferenceMethod.parameters)
    seen = {}

    def body():
        parameter_widgets(values, StatusLine())
        seen["last"] = imgui.get_item_id() == imgui.get_id("time_limit")

    draw_frame(gui, body)
    assert seen["last"]
    assert values["time_limit"] == 0.0, "drawing it changes nothing: 0 = no limit"
