"""Seed 003's figures for method ``pem``: Figure 5 (pem-maps) and Figures 6–7 (pem-offmanifold)."""

from __future__ import annotations

from envstudio.methods.pem import offmanifold
from envstudio.methods.pem.blending import view_blend
from envstudio.plugin import Figure, FigureRequest, Method, ParameterError


def _prepared(request: FigureRequest) -> Method:
    """The session's ``pem`` with ``--param`` applied and its bake file loaded.

    The figures are of a bake file's views (seed 003's arc), so ``coverage=auto``
    plays the file here, and the full orbit (``coverage=orbit``) is refused.
    """
    method = request.method("pem")
    if method.values["coverage"] == "orbit":
        raise ParameterError(
            "pem figures show a .pem file's views: set coverage=file (the full orbit's "
            "numbers: studies/pem-orbit/README.md)"
        )
    method.values["coverage"] = "file"
    method.prepare(request.session.gpu_scene)
    if method.bake is None:
        raise ParameterError(f"pem: {method.status_line()}")
    return method


def draw_maps(request: FigureRequest) -> list[str]:
    """``envstudio figure pem-maps``: the nearest view's inferred maps per model and level."""
    method = _prepared(request)
    blend = view_blend(method.bake.view_space, request.session.camera.position, blend=False)
    display = request.session.renderer.display
    offmanifold.maps_figure(
        method.bake,
        blend.views[0],
        0,
        request.output,
        float(display["exposure"]),
        str(display["tonemap"]),
    )
    return [
        f"{request.output}: view {blend.views[0]} (nearest the camera), part "
        f"{method.bake.parts[0]!r}: rows distant, local α·L, local α, sphere; columns MIP levels"
    ]


def draw_offmanifold(request: FigureRequest) -> list[str]:
    """``envstudio figure pem-offmanifold``: each EM model against a ray trace off the arc."""
    method = _prepared(request)
    results = offmanifold.measure(request.session, method, size=request.size[1])
    offmanifold.figure_image(results, request.output)
    lines = [
        f"{request.output}: rows: views off the baked arc; columns: ray trace, layered PEM, ",
        "sphere at infinity, static EM, and the PTM where the bake has one "
        "(displayed PSNR dB / FLIP, * best)",
    ]
    for r in results:
        cells = "  ".join(f"{m} {v['psnr']:.2f} dB / {v['flip']:.4f}" for m, v in r.metrics.items())
        lines.append(
            f"{r.view.label:>14} (az {r.view.azimuth:.2f}°, el {r.view.elevation:.2f}°): {cells}"
        )
    return lines


MAPS = Figure(
    "pem-maps",
    "seed 003 Figure 5, the nearest view's inferred maps per model and level",
    draw_maps,
)
OFFMANIFOLD = Figure(
    "pem-offmanifold",
    "seed 003 Figures 6-7, layered PEM, sphere at infinity, static EM (and the PTM of a bake "
    "that has one) against a ray trace "
    "midway between baked views and 10 and 20 degrees above the arc",
    draw_offmanifold,
)
