"""Issue 40 item 5: the grid's tiles labelled with their approximation error against the
exact reference of the view, the numbers compare reports, without a saved compare."""

from __future__ import annotations

import pytest

from envstudio.engine.grid_view import tile_layout
from envstudio.engine.session import RenderSession
from envstudio.measure.compare import method_classes, plan_parameters, run_comparison
from envstudio.measure.exact_tiles import SSAA
from envstudio.measure.matching import GlossinessLink
from envstudio.measure.reference_runs import EXACT
from envstudio.ui.grid import GridMetrics, GridState, tile_label
from test_reference_cache import _gradient
from test_render_gl import sphere_scene

NAMES = ("hwconv", "kautz", "mirror")


def test_every_phong_tile_gets_compares_exact_numbers_once_the_view_is_still(gl_ctx):
    size, exponent = (32, 32), 100.0
    session = RenderSession(sphere_scene(_gradient(), rings=16), ctx=gl_ctx)
    plan = plan_parameters(
        method_classes(list(NAMES)), ["trace=false", f"phong_exponent={exponent:g}"]
    )
    comparison = run_comparison(
        session, list(NAMES), size, plan, frames=1, warmup=0, ssaa=SSAA, reference_kind=EXACT
    )
    session.release()

    viewer = RenderSession(sphere_scene(_gradient(), rings=16), ctx=gl_ctx)  # the window's
    hub = viewer.method("reference")  # its panel as the window starts: trace on
    shown = {name: viewer.method(name) for name in NAMES}
    shown["hwconv"].values["phong_exponent"] = exponent
    GlossinessLink().follow(list(shown.values()), shown["hwconv"], hub, viewer.gpu_scene.cube_size)
    clock = iter(range(100))
    metrics = GridMetrics(viewer.renderer, "reference", clock=lambda: float(next(clock)))
    state = GridState()
    state.enter()
    state.tiles = tile_layout(list(NAMES), (0, 0, 100, 32))
    assert all(tile.render_size == size for tile in state.tiles)
    for _ in range(2):  # a change, the look-up (nothing saved)
        metrics.update(state, shown, viewer, hub, None)
    assert all(state.numbers.get(name) is None for name in NAMES)
    for _ in range(6):  # the surface, the shading, the pixels, three tiles
        metrics.update(state, shown, viewer, hub, None)
    for result in comparison.results:
        numbers = state.numbers[result.name]
        assert numbers.relative_error == pytest.approx(result.median_relative_error, abs=1e-3)
        assert numbers.psnr_db == pytest.approx(result.metrics.psnr_db, abs=1e-3)
        assert numbers.against == "exact 32×32"
    label = tile_label(state.tiles[0], state.numbers["hwconv"])
    assert label.endswith("  (exact 32×32)") and " error " in label
    assert "against the exact untraced reference" in state.metrics_note

    viewer.camera.orbit(10.0, 0.0)  # a change: the numbers go until the view is still again
    metrics.update(state, shown, viewer, hub, None)
    assert all(state.numbers[name].psnr_db is None for name in NAMES)
    assert all(state.numbers[name].relative_error is None for name in NAMES)
    metrics.release()
    viewer.release()


def test_microfacet_and_banks_tiles_get_compares_exact_numbers_too(gl_ctx):
    names = ("splitsum", "banks")
    state = GridState()
    state.enter()
    state.tiles = tile_layout(list(names), (0, 0, 48, 24))
    size = state.tiles[0].render_size
    assert all(tile.render_size == size for tile in state.tiles)
    session = RenderSession(sphere_scene(_gradient(), rings=16), ctx=gl_ctx)
    plan = plan_parameters(method_classes(list(names)), ["trace=false"])
    comparison = run_comparison(
        session, list(names), size, plan, frames=1, warmup=0, ssaa=SSAA, reference_kind=EXACT
    )
    session.release()

    viewer = RenderSession(sphere_scene(_gradient(), rings=16), ctx=gl_ctx)
    hub = viewer.method("reference")
    shown = {name: viewer.method(name) for name in names}
    # compare's splitsum: α matched to the reference's N = 200 (the viewer starts at 0.2)
    matched = next(r for r in comparison.results if r.name == "splitsum")
    shown["splitsum"].values["roughness"] = matched.parameters["roughness"]
    GlossinessLink().follow(
        list(shown.values()), shown["splitsum"], hub, viewer.gpu_scene.cube_size
    )
    clock = iter(range(1000))
    metrics = GridMetrics(viewer.renderer, "reference", clock=lambda: float(next(clock)))
    for _ in range(40):  # per model: the surface (and tangents), the shading, the pixels
        metrics.update(state, shown, viewer, hub, None)
        if all(getattr(state.numbers.get(n), "psnr_db", None) is not None for n in names):
            break
    viewer.release()
    for result in comparison.results:
        numbers = state.numbers[result.name]
        assert result.reference_model == {"splitsum": "microfacet", "banks": "banks"}[result.name]
        assert numbers.relative_error == pytest.approx(result.median_relative_error, abs=1e-3)
        assert numbers.psnr_db == pytest.approx(result.metrics.psnr_db, abs=1e-3)
