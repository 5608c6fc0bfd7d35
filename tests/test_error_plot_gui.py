"""The glossiness plot's section drawn in real ImGui/ImPlot frames (ui/error_plot.py)."""

from __future__ import annotations

import math

import pytest
from imgui_bundle import implot

from envstudio.measure.error_curve import NO_EXPONENT, ErrorCurve
from envstudio.ui.error_plot import GlossinessCurve, glossiness_section
from test_imgui_gl import draw_frame, gui, imgui_ctx  # noqa: F401 (fixtures)


@pytest.fixture
def plot_ctx(imgui_ctx):  # noqa: F811
    context = implot.create_context()
    yield
    implot.destroy_context(context)


def test_the_section_draws_a_partial_curve_with_its_progress_and_the_current_n(gui, plot_ctx):  # noqa: F811
    plot = GlossinessCurve((5.0, 50.0, 500.0, 5000.0))
    plot.curve = ErrorCurve(
        list(plot.exponents),
        {"mirror": [0.5, 0.1], "hwconv": [0.01, math.nan]},
        {"mirror": [0.0, 0.0], "hwconv": [0.0, 0.0]},
        [f"banks: reflectance model banks {NO_EXPONENT}"],
    )
    plot.start(["mirror", "hwconv", "banks"])
    picked = []
    for _ in range(2):
        draw_frame(gui, lambda: picked.append(glossiness_section(plot, ["mirror"], 100.0)))
    assert picked == [None, None]
    assert plot.progress() == "0 of 4, waiting for a still view"
