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
    When the ground truth (the reference) is one of the tiles, it converges
    at the tile's size under the shared camera, and every :data:`METRICS_INTERVAL_S`
    seconds each tile of the same reflectance model is measured against it:
    PSNR and LDR-FLIP (core/metrics.py) over the reflector's pixels, on the
    8-bit tile pixels as shown. The numbers follow the reference's progress;
    they are as good as its estimate at that moment (its status line says how
    far it is). A reference cached on disk by ``compare`` is not looked up.
"""

from __future__ import annotations

import math
import statistics
import time
from dataclasses import dataclass, field

import moderngl
import numpy as np
import numpy.typing as npt
from imgui_bundle import imgui

from envstudio.core.metrics import MIN_SIZE, flip, psnr
from envstudio.engine.frame import FrameRenderer
from envstudio.engine.gpu_scene import GpuScene
from envstudio.engine.grid_view import Tile, tile_at
from envstudio.engine.method import Method
from envstudio.scene.camera import OrbitCamera

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
        """ "grid at 1/2 size: 180 ms" while below full size, else None."""
        if self.index == 0:
            return None
        return f"grid at {self.name} size: {self.shown_ms:.0f} ms"


@dataclass
class TileNumbers:
    """A tile's label numbers: ms per frame, and PSNR (dB) and FLIP against the reference."""

    ms: float | None = None
    psnr_db: float | None = None
    flip: float | None = None
    error: str | None = None


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
    """PSNR and FLIP of the tiles against the reference's tile, one tile at a time.

    FLIP takes a few hundred milliseconds a tile on a CPU, so each step (at most
    one every :data:`METRICS_INTERVAL_S`) measures the next tile in turn, and
    reports the time it took so the tile fraction does not count it.

    Parameters
    ----------
    renderer
        The window's renderer: its context and programs draw the reflector mask.
    truth
        The ground truth's method name (the reference); None: no numbers.
    """

    def __init__(self, renderer: FrameRenderer, truth: str | None):
        self.truth = truth
        self._mask_renderer = FrameRenderer(renderer.ctx, renderer.programs)
        self._last = -math.inf
        self._next = 0
        self.spent_ms = 0.0
        """Milliseconds the last step took (0 when none ran this frame)."""

    def due(self, tiles: list[Tile]) -> bool:
        """Whether to measure this frame: the reference is a tile and the interval passed."""
        self.spent_ms = 0.0
        return any(t.name == self.truth for t in tiles) and (
            time.monotonic() - self._last >= METRICS_INTERVAL_S
        )

    def measure(
        self,
        state: GridState,
        methods: dict[str, Method],
        scene: GpuScene,
        camera: OrbitCamera,
        target: moderngl.Framebuffer,
    ) -> None:
        """Measure the next tile in turn of the reference's reflectance model against the
        reference tile, from ``target`` as shown; call after the grid is drawn, before the UI.
        """
        start = time.perf_counter()
        self._step(state, methods, scene, camera, target)
        self._last = time.monotonic()
        self.spent_ms = (time.perf_counter() - start) * 1e3

    def _step(self, state, methods, scene, camera, target) -> None:
        truth_tile = next(t for t in state.tiles if t.name == self.truth)
        reference = methods[self.truth]
        model = reference.values["model"] if "model" in reference.values else None
        w, h = truth_tile.viewport[2:]
        status = getattr(reference, "status", None)
        if getattr(status, "batches", 1) < 1:  # its first pass only: nothing to measure against
            for numbers in state.numbers.values():
                numbers.psnr_db = numbers.flip = None
            state.metrics_note = f"PSNR, FLIP after the {self.truth}'s first batch"
            return
        if min(w, h) < MIN_SIZE:
            state.metrics_note = "tiles too small to measure"
            return
        measured = [
            t
            for t in state.tiles
            if t.name != self.truth
            and t.viewport[2:] == (w, h)
            and (model is None or methods[t.name].reflectance == model)
        ]
        for tile in state.tiles:
            if tile not in measured:
                numbers = state.numbers.setdefault(tile.name, TileNumbers())
                numbers.psnr_db = numbers.flip = None
        if not measured:
            return
        tile = measured[self._next % len(measured)]
        self._next += 1
        mask = self._mask_renderer.reflector_coverage(scene, camera, (w, h))
        if not mask.any():
            state.metrics_note = "no reflector in view"
            return
        shown, truth = _tile_pixels(target, tile), _tile_pixels(target, truth_tile)
        numbers = state.numbers.setdefault(tile.name, TileNumbers())
        numbers.psnr_db, numbers.flip = psnr(shown, truth, mask), flip(shown, truth, mask)
        progress = reference.status_line()
        state.metrics_note = (
            f"PSNR, FLIP against the {self.truth} tile ({model} model), one tile a "
            f"{METRICS_INTERVAL_S:g} s in turn" + (f"; {progress}" if progress else "")
        )

    def release(self) -> None:
        """Free the mask's target; safe twice."""
        self._mask_renderer.release()


def _tile_pixels(target: moderngl.Framebuffer, tile: Tile) -> npt.NDArray[np.float32]:
    """(h, w, 3) float32 in [0, 1]: ``tile`` as shown in ``target``, row 0 at the top."""
    x, y, w, h = tile.viewport
    data = target.read(viewport=(x, y, w, h), components=3, alignment=1)
    pixels = np.frombuffer(data, dtype=np.uint8).reshape(h, w, 3)[::-1]
    return pixels.astype(np.float32) / np.float32(255.0)


def tile_label(tile: Tile, numbers: TileNumbers | None) -> str:
    """The label text: the method and its ms per frame; then PSNR and FLIP where measured."""
    numbers = numbers or TileNumbers()
    if numbers.error:
        return f"{tile.name}: {numbers.error}"
    line = tile.name if numbers.ms is None else f"{tile.name}  {numbers.ms:.1f} ms"
    if numbers.psnr_db is not None and numbers.flip is not None:
        psnr = "inf" if math.isinf(numbers.psnr_db) else f"{numbers.psnr_db:.1f}"
        line += f"\nPSNR {psnr} dB  FLIP {numbers.flip:.3f}"
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
        "show that method alone. Labels: ms per frame; PSNR and FLIP against the reference "
        "tile while it is one of them."
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
