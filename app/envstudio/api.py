"""envmap-studio as a library: scenes, renders and comparisons as NumPy arrays, for notebooks.

::

    import envstudio as es
    scene = es.load_scene("studio")                      # a shipped name or a .toml path
    scene = es.load_scene(env="my.exr", mesh="my.glb")   # or files, as the CLI's --env/--mesh
    img = es.render(scene, "kautz", size=(512, 512), lod_bias=2.0, camera=(115, 20, 3.2))
    ldr = es.display(img, exposure=0, tonemap="aces")    # (h, w, 3) uint8 sRGB, as the PNG
    report = es.compare(scene, ["kautz", "hwconv"], size=(128, 128), time_limit=120)
    report.table, report.images["kautz"], report.reference

Everything runs on one headless context per process, made on first use and reused
(the scene on the GPU is kept while the same scene is rendered again). Bad input
raises the CLI's errors (:class:`envstudio.errors.UserError` subclasses) with its
one-line messages. In Jupyter, :func:`show` displays an image inline and a
:class:`Report` renders as a table.
"""

from __future__ import annotations

import base64
import html
import io
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from envstudio.core.images import to_ldr
from envstudio.engine.session import RenderSession, material_values, render_until_finished
from envstudio.errors import ParameterError
from envstudio.io.scene_setup import build_scene, parse_camera
from envstudio.scene.graph import Scene

__all__ = ["Image", "Report", "compare", "display", "load_scene", "render", "show"]

_SESSION: RenderSession | None = None
_CONTEXT = None
_CAMERA: tuple[float, float, float] = (0.0, 0.0, 0.0)  # the session scene's own camera


def load_scene(
    name_or_path: str | os.PathLike | None = None,
    env: str | os.PathLike | None = None,
    mesh: str | os.PathLike | None = None,
    max_env_width: int | None = None,
) -> Scene:
    """A scene: a shipped name or a ``.toml`` file (default ``studio``), its environment
    and/or reflector replaced by files, as ``--scene``, ``--env`` and ``--mesh`` do."""
    return build_scene(name_or_path, env, mesh, max_env_width)


def _session(scene: Scene) -> RenderSession:
    """The process's session of ``scene``: one context, the scene kept while it is the same."""
    global _SESSION, _CONTEXT, _CAMERA
    if _SESSION is not None and _SESSION.scene is scene:
        camera = _SESSION.camera
        camera.azimuth, camera.elevation, camera.distance = _CAMERA
        return _SESSION
    if _CONTEXT is None:
        from envstudio.gpu.context import create_headless_context

        _CONTEXT = create_headless_context()
    with _CONTEXT:  # current while the old scene is freed and the new one uploaded
        if _SESSION is not None:
            _SESSION.release()
        _SESSION = RenderSession(scene, ctx=_CONTEXT)
    camera = _SESSION.camera
    _CAMERA = (camera.azimuth, camera.elevation, camera.distance)
    return _SESSION


def _size(size: Sequence[int]) -> tuple[int, int]:
    try:
        width, height = (int(v) for v in size)
    except (TypeError, ValueError):
        width = height = 0
    if not (1 <= width <= 16384 and 1 <= height <= 16384):
        raise ParameterError(f"size {size!r}: expected (width, height), each 1..16384")
    return width, height


def render(
    scene: Scene,
    method: str,
    size: Sequence[int] = (512, 512),
    camera: Sequence[float] | None = None,
    time_limit: float | None = None,
    **parameters: object,
) -> npt.NDArray[np.float32]:
    """One frame of ``method``: (h, w, 3) float32 linear radiance, row 0 at the top.

    What ``envstudio render -o X.exr`` writes. ``parameters`` are the method's and the
    display's (``exposure``, ``tonemap``, ``background``); a progressive method (the
    reference) accumulates until it is finished or ``time_limit`` seconds pass.

    Raises
    ------
    ParameterError
        An unknown method or parameter, a value out of range, a bad size or camera.
    """
    width, height = _size(size)
    session = _session(scene)
    with session.ctx:  # current again: another context (a CLI call, a bake) may have taken over
        return _render(session, scene, method, (width, height), camera, time_limit, parameters)


def _render(session, scene, method, size, camera, time_limit, parameters):
    """:func:`render` on ``session``, its context current."""
    instance = session.method(method)
    instance.values.update({p.name: p.default for p in instance.parameters})
    instance.values.update(material_values(scene), ignore_unknown=True)  # as a fresh session
    session.renderer.display.update({p.name: p.default for p in session.renderer.display})
    session.apply(instance, [f"{k}={_text(v)}" for k, v in parameters.items()])
    if time_limit is not None:
        if "time_limit" not in instance.values:
            raise ParameterError(
                f"time_limit: method {method} draws its image in one frame "
                "(only progressive methods, such as reference, take a time limit)"
            )
        instance.values["time_limit"] = time_limit
    _place(session, camera)
    render_until_finished(session, instance, size)
    return session.read_hdr()


def _place(session: RenderSession, camera: Sequence[float] | None) -> None:
    """Put the camera at (azimuth, elevation, distance), degrees and scene units (None: the
    scene's own)."""
    if camera is not None:
        azimuth, elevation, distance = parse_camera(",".join(map(str, camera)))
        session.camera.azimuth, session.camera.elevation = azimuth, elevation
        session.camera.distance = distance


def _text(value: object) -> str:
    """A parameter value as ``--param`` takes it (a colour as r,g,b)."""
    if isinstance(value, (list, tuple, np.ndarray)):
        return ",".join(str(float(v)) for v in value)
    return str(value).lower() if isinstance(value, bool) else str(value)


def display(
    image: npt.ArrayLike, exposure: float = 0.0, tonemap: str = "aces"
) -> npt.NDArray[np.uint8]:
    """(h, w, 3) uint8 sRGB of linear ``image``, as the PNG (exposure in stops, then the tone
    map ``none``, ``reinhard`` or ``aces``)."""
    if tonemap not in ("none", "reinhard", "aces") or not math.isfinite(exposure):
        raise ParameterError(
            f"tonemap={tonemap!r}, exposure={exposure!r}: expected none, reinhard or aces "
            "and a finite exposure"
        )
    return to_ldr(image, exposure, tonemap)


@dataclass
class Image:
    """An image that notebooks show inline (:func:`show`)."""

    pixels: npt.NDArray[np.uint8]

    def _repr_png_(self) -> bytes:
        from PIL import Image as PilImage

        buffer = io.BytesIO()
        PilImage.fromarray(np.ascontiguousarray(self.pixels)).save(buffer, format="PNG")
        return buffer.getvalue()


def show(image: npt.ArrayLike, exposure: float = 0.0, tonemap: str = "aces") -> Image:
    """``image`` for inline display: linear float arrays through :func:`display`, uint8 as is."""
    pixels = np.asarray(image)
    return Image(pixels if pixels.dtype == np.uint8 else display(pixels, exposure, tonemap))


@dataclass
class Report:
    """What :func:`compare` measured: the numbers of ``compare.json`` and the frames.

    Attributes
    ----------
    table : list of dict
        One row per method: ``method``, ``psnr_db``, ``ssim``, ``flip``, ``ms_per_frame``,
        ``reliable``, ``reference`` (the reflectance model it was measured against).
    images : dict
        Method name → (h, w, 3) float32 linear frame as compared.
    reference : (h, w, 3) float32
        The (first) reference frame.
    json : dict
        Everything ``compare.json`` holds.
    """

    table: list[dict]
    images: dict[str, npt.NDArray[np.float32]]
    reference: npt.NDArray[np.float32]
    json: dict

    def _repr_html_(self) -> str:
        columns = list(self.table[0]) if self.table else []
        head = "".join(f"<th>{html.escape(c)}</th>" for c in [*columns, "frame"])
        rows = []
        for row in self.table:
            cells = "".join(f"<td>{html.escape(str(row[c]))}</td>" for c in columns)
            png = base64.b64encode(show(self.images[row["method"]])._repr_png_()).decode()
            thumb = f'<td><img src="data:image/png;base64,{png}" width="96"></td>'
            rows.append(f"<tr>{cells}{thumb}</tr>")
        return f"<table><tr>{head}</tr>{''.join(rows)}</table>"


def compare(
    scene: Scene,
    methods: Sequence[str],
    size: Sequence[int] = (128, 128),
    camera: Sequence[float] | None = None,
    time_limit: float | None = None,
    ssaa: int = 4,
    frames: int = 5,
    cache: bool = True,
    **parameters: object,
) -> Report:
    """``envstudio compare`` in-process: each method against the reference of its model.

    ``parameters`` go to every method that declares them (the reference's included) and to
    the display, as ``--param`` does.
    """
    from envstudio.core.metrics import MIN_SIZE
    from envstudio.measure.compare import method_classes, plan_parameters, run_comparison
    from envstudio.measure.report import to_json

    width, height = _size(size)
    if min(width, height) < MIN_SIZE:
        raise ParameterError(f"size {size!r}: compare needs at least {MIN_SIZE}x{MIN_SIZE}")
    names = list(methods)
    plan = plan_parameters(
        method_classes(names), [f"{k}={_text(v)}" for k, v in parameters.items()]
    )
    session = _session(scene)
    _place(session, camera)
    with session.ctx:
        comparison = run_comparison(
            session,
            names,
            (width, height),
            plan,
            frames=frames,
            warmup=1,
            cache=cache,
            time_limit_s=time_limit,
            ssaa=ssaa,
        )
    report = to_json(comparison)
    table = [
        {
            "method": r.name,
            "psnr_db": report["methods"][r.name]["psnr_db"],
            "ssim": report["methods"][r.name]["ssim"],
            "flip": report["methods"][r.name]["flip"],
            "ms_per_frame": r.frame_ms["median_ms"],
            "reliable": r.reliable,
            "reference": r.reference_model,
        }
        for r in comparison.results
    ]
    images = {r.name: r.hdr for r in comparison.results}
    return Report(table, images, comparison.reference.hdr, report)
