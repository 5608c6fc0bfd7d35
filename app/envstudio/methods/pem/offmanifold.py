"""Where PEMs hold and where they break: views off the baked manifold (seed 003 §6).

Seed 003 Figures 6 and 7 show the layered PEM against the sphere-at-infinity
PEM and a static EM at views the bake never sampled. :func:`measure` renders
``pem`` with each EM model at such views (midway between samples, and 10° and
20° above the arc) and compares them with a ray trace at that exact view (the
bake's own tracer, methods/pem/bake/trace.py, whose composite is the ground truth of the
playback; with the bake's Phong lobe when it was baked glossy, issue 31 part 5),
over the pixels the reflector covers fully: PSNR and FLIP of the
displayed images (core/metrics.py, as ``compare``) and the linear PSNR of the
bake's numbers (peak = the trace's maximum there); the pixels are those one part
covers fully (the bake's interior pixels, where playback and trace see the same
surface). :func:`wobble` is §6's
temporal-stability measure: the mean absolute change of the reflector's pixels
between consecutive frames of a slow camera sweep, per model and for the traced
frames.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from envstudio.core.metrics import compare_images
from envstudio.methods.pem.bake.infer import psnr as linear_psnr
from envstudio.methods.pem.bake.trace import SceneTracer
from envstudio.methods.pem.gpu import MODELS
from envstudio.plugin import to_ldr
from envstudio.scene.camera import OrbitCamera

__all__ = [
    "OffManifoldView",
    "ViewResult",
    "bake_models",
    "measure",
    "offmanifold_views",
    "wobble",
    "wobble_sweep",
]

#: Heights above the arc of seed 003 Figure 7's off-manifold views, degrees.
ELEVATIONS_ABOVE = (10.0, 20.0)


@dataclass(frozen=True)
class OffManifoldView:
    """A view to measure: label, azimuth and elevation in degrees."""

    label: str
    azimuth: float
    elevation: float


@dataclass
class ViewResult:
    """One view's measurements and images.

    Attributes
    ----------
    view : OffManifoldView
    metrics : dict of str to dict
        Per model: ``psnr`` (displayed, dB), ``flip`` (mean over the mask),
        ``psnr_linear`` (dB).
    images : dict of str to (R, R, 3) uint8
        ``trace`` and each model as displayed.
    pixels : int
        Pixels compared.
    """

    view: OffManifoldView
    metrics: dict[str, dict[str, float]] = field(default_factory=dict)
    images: dict[str, npt.NDArray[np.uint8]] = field(default_factory=dict)
    pixels: int = 0

    @property
    def best(self) -> str:
        """The model with the highest displayed PSNR."""
        return max(self.metrics, key=lambda m: self.metrics[m]["psnr"])


def offmanifold_views(view_space: dict) -> list[OffManifoldView]:
    """Seed 003 Figures 6–7's views for a bake: midway between samples, and above the arc.

    Parameters
    ----------
    view_space
        ``ViewSpace.describe()`` of the bake.

    Returns
    -------
    list of OffManifoldView
        Midway between samples at the first, middle and last gap of the azimuths
        (at the first elevation), then 10° and 20° above the highest elevation at
        the middle gap's azimuth.
    """
    az = np.asarray(view_space["azimuths"], dtype=np.float64)
    el = float(np.max(view_space["elevations"]))
    base = float(view_space["elevations"][0])
    if len(az) < 2:
        gaps, middle = [], float(az[0])
    else:
        gaps = sorted({0, (len(az) - 2) // 2, len(az) - 2})
        middle = 0.5 * (az[(len(az) - 2) // 2] + az[(len(az) - 2) // 2 + 1])
    views = [OffManifoldView(f"midway {g}–{g + 1}", 0.5 * (az[g] + az[g + 1]), base) for g in gaps]
    views += [OffManifoldView(f"{h:g}° above", middle, el + h) for h in ELEVATIONS_ABOVE]
    return views


def bake_models(bake) -> tuple[str, ...]:
    """The EM models a bake can show: :data:`MODELS`, without ``ptm`` for a bake without it."""
    return tuple(m for m in MODELS if m != "ptm" or "ptm" in bake.maps)


def _camera(view_space: dict, view: OffManifoldView) -> OrbitCamera:
    return OrbitCamera(
        azimuth=view.azimuth,
        elevation=view.elevation,
        distance=float(view_space["distance"]),
        target=np.asarray(view_space["target"], dtype=np.float64),
        fov_y=float(view_space["fov_y"]),
    )


def _render(session, method, camera: OrbitCamera, size: int, model: str) -> np.ndarray:
    """(R, R, 3) linear radiance of ``pem`` with EM model ``model`` at ``camera``."""
    saved = {k: method.values[k] for k in ("em_model", "snap", "play")}
    method.values.update({"em_model": model, "snap": False, "play": False})
    session.camera.azimuth, session.camera.elevation = camera.azimuth, camera.elevation
    session.camera.distance, session.camera.target = camera.distance, camera.target.copy()
    session.camera.fov_y = camera.fov_y
    session.render_offscreen(method, (size, size))
    method.values.update(saved)
    return session.read_hdr()[..., :3].astype(np.float64)


def measure(
    session,
    method,
    views: list[OffManifoldView] | None = None,
    size: int = 192,
    samples: int = 16,
    seed: int = 7,
) -> list[ViewResult]:
    """Every EM model against a ray trace at each view (module docstring).

    Parameters
    ----------
    session
        A :class:`~envstudio.engine.session.RenderSession` of the bake's scene.
    method
        Its ``pem`` method with a bake loaded (``method.prepare`` done).
    views
        Default :func:`offmanifold_views` of the bake.
    size
        R, square images.
    samples
        Rays per pixel of the trace.
    seed
        The trace's jitter seed.

    Returns
    -------
    list of ViewResult
    """
    bake = method.bake
    if bake is None:
        raise ValueError("no bake loaded")
    space = bake.view_space
    views = offmanifold_views(space) if views is None else views
    tracer = SceneTracer(session.scene)
    glossy = bake.parameters.get("phong_exponent")  # the lobe the bake traced (issue 31.5)
    display = session.renderer.display
    exposure, tonemap = float(display["exposure"]), str(display["tonemap"])
    results = []
    for view in views:
        camera = _camera(space, view)
        traced = tracer.trace(camera, size, samples, seed, glossy)
        mask = (traced.coverage >= 1.0 - 1e-6).any(axis=0)
        reference = traced.composite.astype(np.float64)
        result = ViewResult(view, pixels=int(mask.sum()))
        result.images["trace"] = to_ldr(reference, exposure, tonemap)
        for model in bake_models(bake):
            image = _render(session, method, camera, size, model)
            shown = to_ldr(image, exposure, tonemap)
            result.images[model] = shown
            scores = compare_images(shown / 255.0, result.images["trace"] / 255.0, mask)
            result.metrics[model] = {
                "psnr": scores.psnr_db,
                "flip": scores.flip,
                "psnr_linear": linear_psnr(image[mask], reference[mask]),
            }
        results.append(result)
    return results


def wobble_sweep(
    session,
    method,
    frames: int = 24,
    step: float = 0.25,
    size: int = 128,
    samples: int = 16,
    elevation_above: float = 0.0,
    start: tuple[float, float] | None = None,
) -> dict[str, np.ndarray]:
    """The frame-to-frame changes of a slow sweep, per model (seed 003 §6's wobble and pops).

    Parameters
    ----------
    session, method
        As :func:`measure`.
    frames
        Frames of the sweep, starting at the arc's first azimuth.
    step
        Azimuth step between frames, degrees (a fraction of the bake's step shows
        the blend's transitions).
    size, samples
        Image edge R and the trace's rays per pixel.
    elevation_above
        Degrees above the arc (0: on the manifold).
    start
        (azimuth, elevation) of the first frame in degrees, instead of the arc's first
        azimuth at ``elevation_above`` over its elevation (a full orbit has no arc).

    Returns
    -------
    dict
        Per model and ``trace``: (frames − 1,) the mean absolute difference of
        consecutive displayed images (0–1) over the pixels both frames' traces cover
        fully. Its mean is the wobble (:func:`wobble`); a "pop" (seed 003 §6 on PTMs)
        is one large change where the sweep crosses a sample view, its maximum.
    """
    bake = method.bake
    space = bake.view_space
    tracer = SceneTracer(session.scene)
    glossy = bake.parameters.get("phong_exponent")  # the lobe the bake traced (issue 31.5)
    display = session.renderer.display
    exposure, tonemap = float(display["exposure"]), str(display["tonemap"])
    if start is None:
        start = (float(space["azimuths"][0]), float(space["elevations"][0]) + elevation_above)
    first, elevation = start
    models = bake_models(bake)
    images: dict[str, list[np.ndarray]] = {m: [] for m in (*models, "trace")}
    masks = []
    for k in range(frames):
        view = OffManifoldView(f"sweep {k}", first + k * step, elevation)
        camera = _camera(space, view)
        traced = tracer.trace(camera, size, samples, 11, glossy)  # one jitter: no flicker
        masks.append((traced.coverage >= 1.0 - 1e-6).any(axis=0))
        images["trace"].append(to_ldr(traced.composite, exposure, tonemap) / 255.0)
        for model in models:
            shown = to_ldr(_render(session, method, camera, size, model), exposure, tonemap)
            images[model].append(shown / 255.0)
    return {
        name: np.array(
            [
                np.abs(b - a)[m0 & m1].mean()
                for a, b, m0, m1 in zip(seq, seq[1:], masks, masks[1:], strict=False)
            ]
        )
        for name, seq in images.items()
    }


def wobble(session, method, **kw) -> dict[str, float]:
    """Seed 003 §6's "wobble": mean |frame-to-frame change| over a slow sweep, per model.

    Keywords as :func:`wobble_sweep`; returns per model and ``trace`` the mean of its
    changes.
    """
    return {name: float(np.mean(c)) for name, c in wobble_sweep(session, method, **kw).items()}


def figure_image(results: list[ViewResult], path) -> None:
    """Seed 003 Figures 6–7 as one PNG: per view a row of trace, layered, sphere, static.

    Parameters
    ----------
    results
        :func:`measure`'s results.
    path
        The PNG written (atomically).
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    from envstudio.io.atomic import atomic_path

    columns = ("trace", *results[0].metrics)
    titles = {
        "trace": "ray trace",
        "layered": "layered PEM",
        "sphere": "sphere at infinity",
        "static": "static EM",
        "ptm": "PTM",
    }
    fig, axes = plt.subplots(
        len(results), len(columns), figsize=(2.4 * len(columns), 2.5 * len(results)), dpi=100
    )
    axes = np.atleast_2d(axes)
    for row, result in zip(axes, results, strict=True):
        for ax, name in zip(row, columns, strict=True):
            ax.imshow(result.images[name])
            ax.set_xticks([])
            ax.set_yticks([])
            if name == "trace":
                ax.set_ylabel(result.view.label, fontsize=9)
                ax.set_title(titles[name], fontsize=9)
            else:
                m = result.metrics[name]
                mark = " *" if name == result.best else ""
                ax.set_title(
                    f"{titles[name]}{mark}\n{m['psnr']:.1f} dB, FLIP {m['flip']:.3f}", fontsize=8
                )
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)


def maps_figure(bake, view: int, part: int, path, exposure: float = 0.0, tonemap: str = "aces"):
    """Seed 003 Figure 5 as one PNG: a view's inferred maps of one part, per model and level.

    Parameters
    ----------
    bake
        A loaded bake.
    view, part
        Which maps.
    path
        The PNG written (atomically).
    exposure, tonemap
        The display's settings for the radiance maps (α is shown linearly).
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    from envstudio.core.cubemap import faces_to_cross
    from envstudio.io.atomic import atomic_path

    levels = min(5, len(bake.maps["distant"]))
    rows = [
        ("distant (box)", "distant", slice(0, 3)),
        ("local α·L (ellipsoid)", "local", slice(0, 3)),
        ("local α", "local", 3),
        ("sphere at infinity", "sphere", slice(0, 3)),
    ]
    fig, axes = plt.subplots(len(rows), levels, figsize=(2.6 * levels, 2.2 * len(rows)), dpi=100)
    for r, (label, model, channels) in enumerate(rows):
        for k in range(levels):
            faces = bake.maps[model][k][view, part][..., channels]
            cross = faces_to_cross(faces if faces.ndim == 4 else faces[..., None])
            if faces.ndim == 4:
                image = to_ldr(cross, exposure, tonemap)
            else:
                image = np.clip(cross[..., 0], 0.0, 1.0)
            ax = axes[r, k]
            ax.imshow(image, cmap="gray", vmin=0.0, vmax=1.0, interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                n = bake.em_size >> k
                ax.set_title(f"level {k} ({n}²)", fontsize=9)
            if k == 0:
                ax.set_ylabel(label, fontsize=9)
    fig.suptitle(
        f"{bake.scene}: view {view} (azimuth {bake.cameras[view, 0]:.1f}°), part "
        f"{bake.parts[part]!r}",
        fontsize=10,
    )
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
