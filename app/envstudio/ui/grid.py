"""The window's grid view (issue 29): every method, or the ones picked, side by side, live.

:class:`GridState` holds what the Compare panel's grid section edits (on, the
methods picked) and what the viewer measured (the tiles of the last frame, each
tile's ms per frame, PSNR and FLIP against the reference tile, the tile
fraction). :class:`envstudio.engine.grid_view.GridView` renders the tiles; the
viewer labels them (:func:`draw_labels`) with ImGui's background draw list, so
the labels are drawn under every panel and over the scene, and a PNG capture of
the grid read after the UI is drawn has them.

Tile fraction (:class:`TileScale`)
    On a software rasteriser a grid of every method at the window's size can
    take seconds a frame. The tiles render at a fraction of their size
    (:data:`FRACTIONS`), lowered while the median of the last
    :data:`WINDOW_FRAMES` frame times is over :data:`BUDGET_MS` and raised when
    the next larger fraction is predicted to fit (cost ∝ pixels) with a margin.
    The first :data:`WARM_UP_FRAMES` frames after entering the grid or changing
    the fraction are not counted (programs compile, targets are made).

Reference numbers (:class:`GridMetrics`)
    A reference ``compare`` (or the atlas) saved at this camera, scene and
    display is looked up once the view has stayed unchanged for
    :data:`STILL_S` (measure/cached_reference.py: one per tile, of its
    reflectance model at its matched glossiness). A tile that has one is
    rendered at that reference's size under the same camera and measured
    against it as ``compare --ssaa 1`` measures (its label ends "(cached
    128×128)"); the reference's own tile is not needed. Then each tile of a
    model with an exact untraced reference (phong, issue 40) is measured
    against that reference at its render size, in steps
    (measure/exact_tiles.py): its approximation error, the median relative
    error and PSNR that ``compare --reference exact --param trace=false
    --ssaa 2`` reports at that size (the label ends "(exact 64×64)"); they
    replace a cached reference's numbers. Otherwise, when the
    ground truth (the reference) is one of the tiles, it converges at the
    tile's size under the shared camera, and every :data:`METRICS_INTERVAL_S`
    seconds each tile of the same reflectance model is measured against it:
    PSNR and LDR-FLIP (core/metrics.py) over the reflector's pixels, on the
    8-bit tile pixels as shown. Those numbers follow the reference's progress;
    they are as good as its estimate at that moment (its status line says how
    far it is).
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import moderngl
import numpy as np
import numpy.typing as npt
from imgui_bundle import imgui

from envstudio.core.metrics import MIN_SIZE, flip, psnr
from envstudio.engine.frame import FrameRenderer
from envstudio.engine.grid_view import Tile, tile_at
from envstudio.engine.method import Method, Session
from envstudio.engine.registry import method_class
from envstudio.errors import UserError
from envstudio.gpu.programs import ShaderCompileError
from envstudio.measure.cached_reference import CachedReference, CachedReferences, describe
from envstudio.measure.exact_reference import BANKS_VALUES, EXACT_MODELS
from envstudio.measure.exact_tiles import ExactTiles, TileRequest

FRACTIONS = (1.0, 1 / 2, 1 / 3, 1 / 4, 1 / 6, 1 / 8)
FRACTION_NAMES = ("1", "1/2", "1/3", "1/4", "1/6", "1/8")
BUDGET_MS = 200.0
"""The frame time the grid aims to stay under."""
RAISE_MARGIN = 0.6
"""Raise the fraction only when the prediction is under this share of the budget."""
WINDOW_FRAMES = 5
WARM_UP_FRAMES = 5
EMA = 0.2
"""Weight of the newest frame in each tile's shown ms per frame."""
METRICS_INTERVAL_S = 0.5
STILL_S = 0.3
"""Seconds the view must stay unchanged before the saved references are looked up and the
exact ones evaluated."""
ROUND_TRIP = 1e-9
"""Relative difference under which a tile's N matched from b or α is the hub's N."""
CLICK_POINTS = 4.0
"""A press and release closer than this (window points) is a click, not an orbit."""
LABEL_PAD = 3.0


@dataclass
class TileScale:
    """The fraction of their size the tiles render at, adapted from measured frame times."""

    index: int = 0
    _times: list[float] = field(default_factory=list)
    _skip: int = WARM_UP_FRAMES
    shown_ms: float | None = None
    """The frame time the status line shows: every frame's, smoothed (warm-up included)."""

    @property
    def fraction(self) -> float:
        return FRACTIONS[self.index]

    @property
    def name(self) -> str:
        """ "1", "1/2", ..."""
        return FRACTION_NAMES[self.index]

    @property
    def median_ms(self) -> float | None:
        """Median of the frame times counted since the last change (None before any)."""
        return statistics.median(self._times) if self._times else None

    def restart(self) -> None:
        """Start counting anew (entering the grid): the next frames are warm-up."""
        self._times.clear()
        self._skip = WARM_UP_FRAMES

    def observe(self, frame_ms: float) -> bool:
        """Count one frame's time; returns whether the fraction changed."""
        shown = self.shown_ms
        self.shown_ms = frame_ms if shown is None else (1 - EMA) * shown + EMA * frame_ms
        if self._skip > 0:
            self._skip -= 1
            return False
        self._times = [*self._times[-(WINDOW_FRAMES - 1) :], frame_ms]
        if len(self._times) < WINDOW_FRAMES:
            return False
        median = statistics.median(self._times)
        step = 0
        if median > BUDGET_MS and self.index < len(FRACTIONS) - 1:
            step = 1
        elif self.index > 0:
            larger = (FRACTIONS[self.index - 1] / FRACTIONS[self.index]) ** 2
            if median * larger < RAISE_MARGIN * BUDGET_MS:
                step = -1
        if step:
            self.index += step
            self.restart()
        return bool(step)

    def status(self) -> str | None:
        """ "grid at 1/2 size: 180 ms" while below full size, else None; before the first
        frame's time (a fraction restored from the settings) without the time."""
        if self.index == 0:
            return None
        if self.shown_ms is None:
            return f"grid at {self.name} size"
        return f"grid at {self.name} size: {self.shown_ms:.0f} ms"


@dataclass
class TileNumbers:
    """A tile's label numbers: ms per frame, and PSNR (dB) with FLIP or the median relative
    error against the reference."""

    ms: float | None = None
    psnr_db: float | None = None
    flip: float | None = None
    error: str | None = None
    against: str | None = None
    """What the numbers are against when not the reference's tile ("cached 128×128",
    "exact 64×64")."""
    relative_error: float | None = None
    """The median relative luminance error against the exact reference."""

    def forget(self) -> None:
        """No numbers against a reference (the ms per frame and an error stay)."""
        self.psnr_db = self.flip = self.against = self.relative_error = None


@dataclass
class GridState:
    """What the grid view shows and what was measured.

    Attributes
    ----------
    on : bool
        The grid replaces the single view and the split screen.
    picked : list of str
        The methods shown (empty: every method), kept in registration order.
    tiles : list of Tile
        The last frame's tiles (hit-testing clicks, labels).
    numbers : dict of str to TileNumbers
    metrics_note : str or None
        What the PSNR and FLIP are measured against (or why there are none).
    """

    on: bool = False
    picked: list[str] = field(default_factory=list)
    scale: TileScale = field(default_factory=TileScale)
    tiles: list[Tile] = field(default_factory=list)
    numbers: dict[str, TileNumbers] = field(default_factory=dict)
    metrics_note: str | None = None
    press: tuple[float, float] | None = None

    def as_settings(self) -> dict:
        """What the settings file keeps of the grid: on, the methods picked, the tile scale."""
        return {"on": self.on, "picked": list(self.picked), "scale": self.scale.index}

    def restore(self, saved: object, methods: list[str]) -> list[str]:
        """Apply :meth:`as_settings`' table from the settings file; returns what was rejected.

        A method no longer registered is dropped silently (a plugin may be gone).
        """
        if not isinstance(saved, dict):
            return [f"grid = {saved!r}, expected a table"]
        problems = []
        picked = saved.get("picked", [])
        if isinstance(picked, list) and all(isinstance(n, str) for n in picked):
            self.picked = [name for name in methods if name in picked]
        else:
            problems.append(f"grid.picked = {picked!r}, expected a list of method names")
        scale = saved.get("scale", 0)
        if isinstance(scale, int) and not isinstance(scale, bool) and 0 <= scale < len(FRACTIONS):
            self.scale.index = scale
        else:
            problems.append(f"grid.scale = {scale!r}, expected 0 to {len(FRACTIONS) - 1}")
        on = saved.get("on", False)
        if not isinstance(on, bool):
            problems.append(f"grid.on = {on!r}, expected true or false")
        elif on:
            self.enter()
        return problems

    def names(self, methods: list[str]) -> list[str]:
        """The methods to tile, in ``methods``' order."""
        chosen = [name for name in methods if name in self.picked]
        return chosen or list(methods)

    def enter(self) -> None:
        """Show the grid (timings start anew)."""
        self.on = True
        self.scale.restart()
        self.numbers.clear()
        self.metrics_note = None

    def leave(self) -> None:
        self.on = False
        self.tiles = []
        self.press = None

    def record_times(self, times_ms: dict[str, float], errors: dict[str, str]) -> None:
        """Blend each tile's frame time into its shown ms per frame; note the failed tiles."""
        for name, message in errors.items():
            self.numbers.setdefault(name, TileNumbers()).error = message
        for name, ms in times_ms.items():
            self.numbers.setdefault(name, TileNumbers()).error = None
            numbers = self.numbers.setdefault(name, TileNumbers())
            numbers.ms = ms if numbers.ms is None else (1 - EMA) * numbers.ms + EMA * ms

    def click(
        self,
        press: tuple[float, float],
        release: tuple[float, float],
        scale: tuple[float, float],
        buffer_height: int,
    ) -> str | None:
        """The method of the tile clicked, if ``press`` and ``release`` (window points, origin
        top-left) make a click on one (else None: a drag, or a gap).

        Parameters
        ----------
        press, release
            Where the button went down and up, window points.
        scale
            Framebuffer pixels per point (x, y): more than 1 on a HiDPI screen.
        buffer_height
            The framebuffer's height in pixels (GL rows count from the bottom).
        """
        if math.dist(press, release) > CLICK_POINTS:
            return None
        x, y = release[0] * scale[0], buffer_height - release[1] * scale[1]
        tile = tile_at(self.tiles, x, y)
        return tile.name if tile else None


class GridMetrics:
    """PSNR and FLIP of the tiles against a reference: one ``compare`` saved, the exact
    reference, else the reference's tile; one piece of work at a time.

    Cached references (:class:`envstudio.measure.cached_reference.CachedReferences`)
        While the camera, the scene, the display or a tile's parameters change, nothing
        is looked up. Once they have stayed the same for :data:`STILL_S`, the saved
        references of this view are looked up once (a hash of the scene, one key per
        tile and candidate), and then, one tile a step, each tile that has one is
        rendered at that reference's size and measured against it. Its label says
        so ("cached 128×128"). A change clears those numbers.
    The exact reference (:class:`envstudio.measure.exact_tiles.ExactTiles`)
        Then, for the tiles of a model with an exact untraced evaluation
        (exact_reference.EXACT_MODELS), the reference at the tile's f_λ, k_d and the
        Phong exponent its glossiness is matched to (the hub's N where the tile's is its
        round trip, as ``compare`` holds the reference's N), evaluated at the tile's render
        size in steps, and each such tile measured against it: median relative error and
        PSNR, as ``compare --reference exact --param trace=false`` reports them at that
        size and its ``--ssaa`` (exact_tiles.SSAA) ("exact 64×64"). They replace
        a cached reference's numbers; a change clears them.
    The reference's tile
        Tiles with no cached reference, of the live reference's model and size, are
        measured against the reference's tile as shown, one a step.

    FLIP takes a few hundred milliseconds a tile on a CPU, so a step runs at most
    every :data:`METRICS_INTERVAL_S`, and its time is reported (:attr:`spent_ms`) so
    the tile fraction does not count it.

    Parameters
    ----------
    renderer
        The window's renderer: its context and programs draw the reflector mask.
    truth
        The ground truth's method name (the reference); None: no numbers.
    clock
        Seconds, monotonic (:func:`time.monotonic`).
    """

    def __init__(
        self,
        renderer: FrameRenderer,
        truth: str | None,
        clock: Callable[[], float] = time.monotonic,
    ):
        self.truth = truth
        self._clock = clock
        self._mask_renderer = FrameRenderer(renderer.ctx, renderer.programs)
        self._cached = self._exact = None
        if truth is not None:
            self._cached = CachedReferences(renderer.ctx, renderer.programs, method_class(truth))
            self._exact = ExactTiles(renderer.ctx, renderer.programs)
        self._last = -math.inf
        self._next = 0
        self._view: tuple | None = None
        self._still_since = 0.0
        self._looked_up = False
        self._queue: list[tuple[str, CachedReference]] = []
        self._found: dict[str, CachedReference] = {}
        self._described: dict[Path, str] = {}
        self._notes = {"cached": None, "exact": None, "live": None}
        self.spent_ms = 0.0
        """Milliseconds the last step took (0 when none ran this frame)."""

    def update(
        self,
        state: GridState,
        methods: dict[str, Method],
        session: Session,
        hub: Method | None,
        target: moderngl.Framebuffer,
    ) -> None:
        """Call every frame after the grid is drawn, before the UI: notice changes, and when
        a step is due, look up, measure a tile against a cached reference, take a step of
        the exact reference's, or measure a tile against the reference's tile (from
        ``target`` as shown).

        Parameters
        ----------
        methods
            The tiles' methods by name.
        session
            The viewer's session: scene, camera, display settings.
        hub
            The ground truth's instance (its panel's values start the cache keys; its N is
            the one the grid's matching goes through); None: no cached references.
        """
        self.spent_ms = 0.0
        if self.truth is None:
            return
        start, now = time.perf_counter(), self._clock()
        view = _view_key(state, methods, session, hub)
        if view != self._view:  # moving or edited: the cached numbers no longer hold
            self._view, self._still_since, self._looked_up = view, now, False
            self._queue, self._found, self._described = [], {}, {}
            self._exact.clear()
            for numbers in state.numbers.values():
                if numbers.against is not None:
                    numbers.forget()
            self._notes["cached"] = self._notes["exact"] = None
        elif now - self._last >= METRICS_INTERVAL_S:
            if not self._looked_up and now - self._still_since >= STILL_S and hub is not None:
                self._look_up(state, methods, session, hub)
            elif self._queue:
                self._measure_cached(state, methods, session)
            elif self._exact.pending:
                self._measure_exact(state, session)
            elif any(t.name == self.truth for t in state.tiles):
                self._step(state, methods, session.gpu_scene, session.camera, target)
            else:
                self._compose(state)
                return
            self._last = now
            self.spent_ms = (time.perf_counter() - start) * 1e3
        self._compose(state)

    def _look_up(self, state, methods, session, hub) -> None:
        self._looked_up = True
        if self._cached is None:
            return
        shown = [methods[t.name] for t in state.tiles]
        cube = session.gpu_scene.cube_size
        self._cached.forget()
        self._found = self._cached.find(session, hub, shown, hub, cube)
        self._queue = list(self._found.items())
        self._exact.start(
            {
                t.name: TileRequest(
                    methods[t.name], self._exact_values(methods[t.name], hub, cube), t.render_size
                )
                for t in state.tiles
                if t.name != self.truth
                and methods[t.name].reflectance in EXACT_MODELS
                and min(t.render_size) >= MIN_SIZE
            }
        )
        if not self._found:
            self._notes["cached"] = (
                "no reference saved by compare at this camera (R: the scene's camera)"
            )

    def _measure_cached(self, state, methods, session) -> None:
        name, found = self._queue.pop(0)
        display = session.renderer.display.as_dict()
        try:
            result = self._cached.measure(session, methods[name], found, display)
        except (UserError, ShaderCompileError) as exc:  # its tile says why, if it fails too
            self._notes["cached"] = f"{name} at {describe(found)}: {str(exc).splitlines()[0]}"
            result = None
        numbers = state.numbers.setdefault(name, TileNumbers())
        if result is None:
            numbers.psnr_db = numbers.flip = numbers.against = None
            return
        numbers.psnr_db, numbers.flip = result.psnr_db, result.flip
        numbers.against = f"cached {found.size[0]}×{found.size[1]}"
        model = found.values.get("model", "")
        self._described[found.path] = f"{model} {describe(found)}: {result.reference}".strip()
        names = ", ".join(n for n in methods if n in self._found)
        self._notes["cached"] = (
            f"{names}: PSNR, FLIP against the reference compare saved at this camera "
            f"({'; '.join(self._described.values())}), each method rendered at its size, "
            "one sample per pixel"
        )

    def _exact_values(self, method: Method, hub: Method, cube: int) -> dict[str, object]:
        """The exact reference's f_λ, k_d and N at ``method``'s tile: the values ``compare``
        gives the reference of its model (CachedReferences.candidates' first), with the
        hub's N where the tile's matched N is its round trip (N → b → N)."""
        values = self._cached.candidates(hub, method, hub, cube)[0]
        exact = {"model": method.reflectance, "fresnel": values["fresnel"], "kd": values["kd"]}
        if method.reflectance == "banks":  # its lobe's own values, and no exponent
            return exact | {name: values[name] for name in BANKS_VALUES}
        exponent, hub_exponent = float(values["phong_exponent"]), hub.values["phong_exponent"]
        if math.isclose(exponent, hub_exponent, rel_tol=ROUND_TRIP):
            exponent = float(hub_exponent)
        return exact | {"phong_exponent": exponent}

    def _measure_exact(self, state: GridState, session: Session) -> None:
        measured = self._exact.step(session, session.renderer.display.as_dict())
        if measured is None:
            self._notes["exact"] = "evaluating the exact reference…"
            return
        name, result = measured
        numbers = state.numbers.setdefault(name, TileNumbers())
        numbers.forget()
        tile = next((t for t in state.tiles if t.name == name), None)
        if result is None or tile is None:
            return
        numbers.psnr_db, numbers.relative_error = result.psnr_db, result.median_relative_error
        w, h = tile.render_size
        numbers.against = f"exact {w}×{h}"
        exact = [n for n, m in state.numbers.items() if m.against and m.against.startswith("exact")]
        self._notes["exact"] = (
            f"{', '.join(exact)}: approximation error (median relative error, PSNR) against "
            f"the exact untraced reference at the tile's size, {self._exact.ssaa}×"
            f"{self._exact.ssaa} samples a pixel, as compare --reference exact measures"
        )

    def _compose(self, state: GridState) -> None:
        notes = [note for note in self._notes.values() if note]
        state.metrics_note = "; ".join(notes) if notes else None

    def _step(self, state, methods, scene, camera, target) -> None:
        truth_tile = next(t for t in state.tiles if t.name == self.truth)
        reference = methods[self.truth]
        model = reference.values["model"] if "model" in reference.values else None
        w, h = truth_tile.viewport[2:]
        status = getattr(reference, "status", None)
        cached = {name for name, n in state.numbers.items() if n.against is not None}
        if getattr(status, "batches", 1) < 1:  # its first pass only: nothing to measure against
            for name, numbers in state.numbers.items():
                if name not in cached:
                    numbers.psnr_db = numbers.flip = None
            self._notes["live"] = f"PSNR, FLIP after the {self.truth}'s first batch"
            return
        if min(w, h) < MIN_SIZE:
            self._notes["live"] = "tiles too small to measure"
            return
        measured = [
            t
            for t in state.tiles
            if t.name != self.truth
            and t.name not in cached
            and t.viewport[2:] == (w, h)
            and (model is None or methods[t.name].reflectance == model)
        ]
        for tile in state.tiles:
            if tile not in measured and tile.name not in cached:
                state.numbers.setdefault(tile.name, TileNumbers()).forget()
        if not measured:
            return
        tile = measured[self._next % len(measured)]
        self._next += 1
        mask = self._mask_renderer.reflector_coverage(scene, camera, (w, h))
        if not mask.any():
            self._notes["live"] = "no reflector in view"
            return
        shown, truth = _tile_pixels(target, tile), _tile_pixels(target, truth_tile)
        numbers = state.numbers.setdefault(tile.name, TileNumbers())
        numbers.psnr_db, numbers.flip = psnr(shown, truth, mask), flip(shown, truth, mask)
        progress = reference.status_line()
        self._notes["live"] = (
            f"PSNR, FLIP against the {self.truth} tile ({model} model), one tile a "
            f"{METRICS_INTERVAL_S:g} s in turn" + (f"; {progress}" if progress else "")
        )

    def release(self) -> None:
        """Free the mask's target, the cached and exact references' objects; safe twice."""
        self._mask_renderer.release()
        if self._cached is not None:
            self._cached.release()
            self._exact.release()


def _view_key(
    state: GridState, methods: dict[str, Method], session: Session, hub: Method | None
) -> tuple:
    """What a cached reference's numbers depend on, cheap to compare every frame: the camera,
    the scene's revisions and transforms, the display, and every tile's (and the hub's)
    parameter values."""
    scene = session.gpu_scene
    nodes = tuple(node.transform.matrix().tobytes() for node in session.scene.nodes)
    values = [(t.name, repr(methods[t.name].values.as_dict())) for t in state.tiles]
    return (
        session.camera.view_matrix().tobytes(),
        scene.environment_revision,
        scene.geometry_revision,
        nodes,
        repr(session.renderer.display.as_dict()),
        tuple(values),
        repr(hub.values.as_dict()) if hub is not None else None,
        state.scale.index,  # a new fraction clears the numbers (GridState.numbers)
    )


def _tile_pixels(target: moderngl.Framebuffer, tile: Tile) -> npt.NDArray[np.float32]:
    """(h, w, 3) float32 in [0, 1]: ``tile`` as shown in ``target``, row 0 at the top."""
    x, y, w, h = tile.viewport
    data = target.read(viewport=(x, y, w, h), components=3, alignment=1)
    pixels = np.frombuffer(data, dtype=np.uint8).reshape(h, w, 3)[::-1]
    return pixels.astype(np.float32) / np.float32(255.0)


def tile_label(tile: Tile, numbers: TileNumbers | None) -> str:
    """The label text: the method and its ms per frame; then PSNR and FLIP, or PSNR and the
    median relative error, where measured."""
    numbers = numbers or TileNumbers()
    if numbers.error:
        return f"{tile.name}: {numbers.error}"
    line = tile.name if numbers.ms is None else f"{tile.name}  {numbers.ms:.1f} ms"
    if numbers.psnr_db is not None:
        psnr = "inf" if math.isinf(numbers.psnr_db) else f"{numbers.psnr_db:.1f}"
        line += f"\nPSNR {psnr} dB"
        if numbers.flip is not None:
            line += f"  FLIP {numbers.flip:.3f}"
        if numbers.relative_error is not None:
            line += f"  error {100 * numbers.relative_error:.2f} %"
        if numbers.against:
            line += f"  ({numbers.against})"
    return line


def draw_labels(
    state: GridState, scale: tuple[float, float], buffer_height: int
) -> list[tuple[float, float, float, float]]:
    """Each tile's label at its top-left, on ImGui's background draw list (over the scene,
    under every window); between ``new_frame`` and ``render``.

    Parameters
    ----------
    scale
        Framebuffer pixels per window point (x, y).
    buffer_height
        The framebuffer's height in pixels.

    Returns
    -------
    list of (x, y, w, h)
        The labels' boxes in window points (origin top-left).
    """
    draw = imgui.get_background_draw_list()
    text_colour = imgui.get_color_u32((1.0, 1.0, 1.0, 1.0))
    box_colour = imgui.get_color_u32((0.0, 0.0, 0.0, 0.6))
    boxes = []
    for tile in state.tiles:
        x, y, _, h = tile.viewport
        left = x / scale[0]
        top = (buffer_height - (y + h)) / scale[1]
        text = tile_label(tile, state.numbers.get(tile.name))
        size = imgui.calc_text_size(text)
        right, bottom = left + tile.viewport[2] / scale[0], top + tile.viewport[3] / scale[1]
        box = (
            left,
            top,
            min(size.x + 2 * LABEL_PAD, right - left),
            min(size.y + 2 * LABEL_PAD, bottom - top),
        )
        draw.push_clip_rect((left, top), (right, bottom), True)  # a label stays in its tile
        draw.add_rect_filled((box[0], box[1]), (box[0] + box[2], box[1] + box[3]), box_colour)
        draw.add_text((left + LABEL_PAD, top + LABEL_PAD), text_colour, text)
        draw.pop_clip_rect()
        boxes.append(box)
    return boxes


def grid_section(methods: list[str], state: GridState) -> None:
    """The Compare panel's grid controls: on/off and the methods picked (none: all)."""
    imgui.separator()
    changed, on = imgui.checkbox("grid view", state.on)
    if changed:
        state.enter() if on else state.leave()
    imgui.set_item_tooltip(
        "Every method (or the ones ticked below) in tiles under one camera; click a tile to "
        "show that method alone. Labels: ms per frame; once the view stops changing, the "
        "approximation error (PSNR, median relative error) against the exact reference where "
        "the model has one, else PSNR and FLIP against a reference compare saved at this "
        "camera, else against the reference tile while it is one of them."
    )
    if not state.on:
        return
    for name in methods:
        ticked, value = imgui.checkbox(f"{name}##grid", name in state.picked)
        if ticked:
            state.picked = [
                n for n in methods if (n == name and value) or (n != name and n in state.picked)
            ]
    if not state.picked:
        imgui.text_disabled("none ticked: every method")
    if state.metrics_note:
        imgui.text_wrapped(state.metrics_note)
