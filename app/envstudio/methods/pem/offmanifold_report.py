"""``envstudio compare``'s section for ``pem``: seed 003 Figures 6–7 and §6's wobble."""

from __future__ import annotations

from pathlib import Path

from envstudio.methods.pem import offmanifold
from envstudio.plugin import Method, ReportExtra, Session

__all__ = ["offmanifold_extra"]


def offmanifold_extra(session: Session, method: Method, out_dir: Path) -> ReportExtra:
    """The EM models off the baked views, measured (methods/pem/offmanifold.py).

    At views midway between baked samples and 10° and 20° above the arc, each
    EM model against a ray trace at that exact view; the views where the
    layered PEM is not best are named. Then the mean frame-to-frame change
    along a slow sweep, per model and for the traced frames. The camera is put
    back as it was; ``out_dir`` receives ``pem_offmanifold.png``.

    Parameters
    ----------
    session
        The session on show.
    method
        Its ``pem`` method with a bake file loaded.
    out_dir
        The report's folder.
    """
    saved = (session.camera.azimuth, session.camera.elevation, session.camera.distance)
    saved_target, saved_fov = session.camera.target.copy(), session.camera.fov_y
    try:
        results = offmanifold.measure(session, method)
        motion = offmanifold.wobble(session, method)
    finally:
        camera = session.camera
        camera.azimuth, camera.elevation, camera.distance = saved
        camera.target, camera.fov_y = saved_target, saved_fov
    offmanifold.figure_image(results, out_dir / "pem_offmanifold.png")
    rows = [
        [
            r.view.label,
            f"{r.view.azimuth:.2f}",
            f"{r.view.elevation:.2f}",
            *(f"{r.metrics[m]['psnr']:.2f} / {r.metrics[m]['flip']:.4f}" for m in r.metrics),
            r.best,
        ]
        for r in results
    ]
    losers = [r.view.label for r in results if r.best != "layered"]
    verdict = (
        "The layered PEM is best at every view."
        if not losers
        else f"The layered PEM is not best at: {', '.join(losers)}."
    )
    wobble_text = ", ".join(f"{k} {v:.4f}" for k, v in motion.items())
    return ReportExtra(
        title="PEM off the manifold (seed 003 Figures 6-7)",
        text=(
            "Displayed PSNR (dB) / mean FLIP over the reflector's fully covered pixels, "
            f"against a ray trace at each view. {verdict} Wobble (mean absolute "
            f"frame-to-frame change, 0-1, along a 0.25° sweep): {wobble_text}."
        ),
        columns=["view", "azimuth °", "elevation °", *results[0].metrics, "best"],
        rows=rows,
        data={
            "views": [
                {
                    "label": r.view.label,
                    "azimuth": r.view.azimuth,
                    "elevation": r.view.elevation,
                    "pixels": r.pixels,
                    "metrics": r.metrics,
                    "best": r.best,
                }
                for r in results
            ],
            "layered_not_best": losers,
            "wobble": motion,
        },
        images=[("pem_offmanifold.png", "trace | layered | sphere | static per view")],
    )
