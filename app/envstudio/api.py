"""envmap-studio as a library: scenes, renders and comparisons as NumPy arrays, for notebooks.

::

    import envstudio as es
    scene = es.load_scene("studio")                      # a shipped name or a .toml path
    scene = es.load_scene(env="my.exr", mesh="my.glb")   # or files, as the CLI's --env/--mesh
    img = es.render(scene, "kautz", size=(512, 512), lod_bias=2.0, camera=(115, 20, 3.2))
    ldr = es.display(img, exposure=0, tonemap="aces")    # (h, w, 3) uint8 sRGB, as the PNG
    report = es.compare(scene, ["kautz", "hwconv"], size=(128, 128), time_limit=120)
    report.table, report.images["kautz"], report.reference
    curve = es.error_curve(scene, ["kautz", "hwconv"])  # error against N, exact reference

Everything runs on one headless context per process, made on first use and reused
(the scene on the GPU is kept while the same scene is rendered again). Bad input
raises the CLI's errors (:class:`envstudio.errors.UserError` subclasses) with its
one-line messages. In Jupyter, :func:`show` displays an image inline and a
:class:`Report` renders as a table.
"""

from __future__ import annotations

import base64
import copy
import html
import io
import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from envstudio import api_arguments as check
from envstudio.core.images import to_ldr
from envstudio.engine.session import RenderSession, render_until_finished
from envstudio.errors import InputFileError, ParameterError, file_error
from envstudio.io.scene_setup import build_scene
from envstudio.measure.time_limit import check_time_limit
from envstudio.scene.graph import Scene

__all__ = [
    "Image",
    "Report",
    "compare",
    "display",
    "error_curve",
    "load_scene",
    "render",
    "show",
]

_SESSION: RenderSession | None = None
_CONTEXT = None


def load_scene(
    name_or_path: str | os.PathLike | None = None,
    env: str | os.PathLike | None = None,
    mesh: str | os.PathLike | None = None,
    max_env_width: int | None = None,
) -> Scene:
    """A scene: a shipped name or a ``.toml`` file (default ``studio``), its environment
    and/or reflector replaced by files, as ``--scene``, ``--env`` and ``--mesh`` do.

    Raises
    ------
    InputFileError
        A file that is missing, unreadable or not what was expected.
    ParameterError
        An argument of the wrong type, or a ``max_env_width`` under 8 (as
        ``--max-env-width``).
    """
    check.path(name_or_path, "name_or_path", "a shipped scene name or a .toml file")
    check.path(env, "env", "an .exr or .hdr file")
    check.path(mesh, "mesh", "a mesh file (OBJ, PLY, STL, OFF, GLB)")
    if max_env_width is not None:
        check.integer(max_env_width, "max_env_width")
    try:
        return build_scene(name_or_path, env, mesh, max_env_width)
    except OSError as exc:
        line = file_error(exc)
        if line is None:
            raise
        raise InputFileError(line) from exc


@contextmanager
def _session(scene: Scene) -> Iterator[RenderSession]:
    """The process's session of ``scene``, its context current, its camera the scene's own.

    One context per process; the scene on the GPU is kept while the same scene is rendered
    again, and every method's values and the display's are reset to a fresh session's (what
    one call set never leaks into the next). A call that fails inside leaves no session
    behind (whatever it half-built is freed), so the next call starts from a fresh one.
    """
    global _SESSION, _CONTEXT
    if _CONTEXT is None:
        from envstudio.gpu.context import create_headless_context

        _CONTEXT = create_headless_context()
    with _CONTEXT:  # current again: another context (a CLI call, a bake) may have taken over
        try:
            if _SESSION is None or _SESSION.scene is not scene:
                _release_session()
                _SESSION = RenderSession(scene, ctx=_CONTEXT)
            _SESSION.camera = copy.deepcopy(scene.camera)  # placed per call, the scene's kept
            _SESSION.reset_values()
            yield _SESSION
        except BaseException:
            with suppress(Exception):  # a half-built session may not free cleanly; the error
                _release_session()  # that broke it is the one to report
            raise


def _release_session() -> None:
    """Forget the process's session, if any, and free it (its context current)."""
    global _SESSION
    session, _SESSION = _SESSION, None
    if session is not None:
        session.release()


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
        An unknown method or parameter, a value out of range or of the wrong type, a bad
        scene, size, camera or time limit.
    """
    check.scene(scene)
    cls = check.method(method)
    size = check.size(size)
    camera = check.camera(camera)
    assignments = check.method_assignments(cls, parameters)
    if time_limit is not None:
        time_limit = check_time_limit(time_limit, "time_limit")
        if "time_limit" not in {p.name for p in cls.parameters}:
            raise ParameterError(
                f"time_limit: method {method} draws its image in one frame "
                "(only progressive methods, such as reference, take a time limit)"
            )
    with _session(scene) as session:
        instance = session.method(method)
        session.apply(instance, assignments)
        if time_limit is not None:
            instance.values["time_limit"] = time_limit
        _place(session, camera)
        render_until_finished(session, instance, size)
        return session.read_hdr()


def _place(session: RenderSession, camera: tuple[float, float, float] | None) -> None:
    """Put the camera at (azimuth, elevation, distance), degrees and scene units (None: the
    scene's own)."""
    if camera is not None:
        session.camera.azimuth, session.camera.elevation, session.camera.distance = camera


def display(
    image: npt.ArrayLike, exposure: float = 0.0, tonemap: str = "aces"
) -> npt.NDArray[np.uint8]:
    """(h, w, 3) uint8 sRGB of linear ``image``, as the PNG (exposure in stops, then the tone
    map ``none``, ``reinhard`` or ``aces``).

    Raises
    ------
    ParameterError
        ``image`` not (h, w, 3) finite numbers, or ``exposure`` and ``tonemap`` outside the
        display's declarations (as ``--param exposure=...``).
    """
    pixels = check.linear_image(image)
    exposure = check.display_setting("exposure", exposure)
    tonemap = check.display_setting("tonemap", tonemap)
    return to_ldr(pixels, exposure, tonemap)


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
    """``image`` for inline display: (h, w, 3) linear arrays through :func:`display`,
    (h, w, 3) or (h, w, 4) uint8 sRGB as is.

    Raises
    ------
    ParameterError
        As :func:`display`, or a uint8 array of another shape.
    """
    pixels = check.srgb_image(image)
    return Image(display(image, exposure, tonemap) if pixels is None else pixels)


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
    reference: str = "exact",
    **parameters: object,
) -> Report:
    """``envstudio compare`` in-process: each method against the reference of its model.

    ``methods`` is a list of names (or one string of comma-separated names, as
    ``--methods``). ``parameters`` go to every method that declares them (the reference's
    included) and to the display, as ``--param`` does. ``reference`` is ``--reference``:
    ``"exact"`` (the untraced model evaluated exactly where it has an exact evaluation) or
    ``"montecarlo"``.

    Raises
    ------
    ParameterError
        An unknown method or parameter, a value out of range or of the wrong type, a bad
        scene, size, camera, time limit, ``ssaa``, ``frames`` or ``cache``; a camera that
        sees no reflector.
    """
    from envstudio.core.metrics import MIN_SIZE
    from envstudio.measure.compare import (
        check_ssaa,
        method_classes,
        plan_parameters,
        run_comparison,
    )
    from envstudio.measure.reference_runs import REFERENCE_KINDS
    from envstudio.measure.report import to_json

    check.scene(scene)
    names = check.methods(methods)
    size = check.size(size)
    if min(size) < MIN_SIZE:
        raise ParameterError(f"size {size!r}: compare needs at least {MIN_SIZE}x{MIN_SIZE}")
    camera = check.camera(camera)
    if time_limit is not None:
        time_limit = check_time_limit(time_limit, "time_limit")
    check_ssaa(ssaa, size)
    frames = check.integer(frames, "frames", 1)
    cache = check.flag(cache, "cache")
    if reference not in REFERENCE_KINDS:
        raise ParameterError(
            f"reference {reference!r}: expected one of {', '.join(REFERENCE_KINDS)}"
        )
    plan = plan_parameters(method_classes(names), check.assignments(parameters))
    with _session(scene) as session:
        _place(session, camera)
        comparison = run_comparison(
            session,
            names,
            size,
            plan,
            frames=frames,
            warmup=1,
            cache=cache,
            time_limit_s=time_limit,
            ssaa=ssaa,
            reference_kind=reference,
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


def error_curve(
    scene: Scene,
    methods: Sequence[str],
    exponents: Sequence[float] = (5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000),
    size: Sequence[int] = (64, 64),
    ssaa: int = 2,
    camera: Sequence[float] | None = None,
    **parameters: object,
) -> dict:
    """Each method's approximation error against the exact reference at each Phong exponent.

    At each N, what ``compare --reference exact --param trace=false --param
    phong_exponent=N`` measures (measure/error_curve.py): a LOD bias or a GGX α matched to N
    as compare matches it. ``parameters`` go to every method that declares them, as
    :func:`compare`'s do (not ``phong_exponent`` or ``trace``: the curve sets them).

    Returns
    -------
    dict
        ``{"exponents": [...], "methods": {name: {"median_relative_error": [...],
        "psnr_db": [...]}}}``, one value per exponent (NaN where a method refuses its values
        at that N), and ``"notes"``: the methods left out (banks, whose lobe no Phong
        exponent sets, and a plugin's model with no exact reference) and the points
        missing, one line each.

    Raises
    ------
    ParameterError
        An unknown method or parameter, a value out of range or of the wrong type, a bad
        scene, size, camera, ``ssaa`` or exponent (each within the range of every method
        declaring ``phong_exponent``); no method with an exact reference; a camera that
        sees no reflector.
    """
    from envstudio.core.metrics import MIN_SIZE
    from envstudio.measure import error_curve as curve
    from envstudio.measure.compare import check_ssaa, method_classes, plan_parameters

    check.scene(scene)
    names = check.methods(methods)
    size = check.size(size)
    if min(size) < MIN_SIZE:
        raise ParameterError(f"size {size!r}: the curve needs at least {MIN_SIZE}x{MIN_SIZE}")
    camera = check.camera(camera)
    check_ssaa(ssaa, size)
    values = curve.check_exponents(exponents, names)
    for name in ("phong_exponent", "trace"):
        if name in parameters:
            raise ParameterError(f"{name}: error_curve sets it (exponents; trace=false)")
    assignments = check.assignments(parameters)
    plan_parameters(method_classes(names), assignments)
    with _session(scene) as session:
        _place(session, camera)
        measured = curve.error_curve(session, names, values, size, ssaa, assignments)
    return measured.as_dict()
