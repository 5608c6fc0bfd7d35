"""Grid view: several methods at once, one tile each, under one shared camera (issue 29).

The view's rectangle is cut into ``columns x rows`` tiles (the grid whose tiles
are the largest squares-ish fit, :func:`grid_shape`), in reading order::

    +---------+---------+---------+
    | mirror  | hwconv  | kautz   |    tile i: column i % columns, row i // columns
    +---------+---------+---------+    (row 0 at the top)
    | banks   | ref     |         |
    +---------+---------+---------+

Tiles are separated by :data:`GAP` pixels of the cleared background. Each tile is
rendered by its own :class:`FrameRenderer` (so each keeps its HDR target and its
pass timer) at the tile's size times a fraction (1, 1/2, ...) and presented, tone
mapped, into the tile's viewport; at fraction 1 a tile is pixel for pixel what
``envstudio render`` draws at that size. Below 1 the display pass stretches the
smaller frame over the tile (nearest texel).

Coordinates: tiles are GL viewports, framebuffer pixels with the origin at the
bottom-left, as :func:`envstudio.ui.docking.gl_viewport` gives the view.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import moderngl

from envstudio.engine.frame import FrameRenderer
from envstudio.engine.frame_stats import FrameStats
from envstudio.engine.method import Method
from envstudio.errors import UserError
from envstudio.gpu.programs import ShaderCompileError
from envstudio.scene.camera import OrbitCamera
from envstudio.shading.gpu_scene import GpuScene

GAP = 2
"""Pixels of background between neighbouring tiles."""


@dataclass(frozen=True)
class Tile:
    """One method's place in the grid.

    Attributes
    ----------
    name : str
        The method shown.
    viewport : (x, y, w, h)
        GL viewport in the target, framebuffer pixels, origin bottom-left.
    render_size : (w, h)
        Resolution the method renders at (the viewport's size times the fraction).
    """

    name: str
    viewport: tuple[int, int, int, int]
    render_size: tuple[int, int]

    def contains(self, x: float, y: float) -> bool:
        """Whether the GL pixel position (x, y) (origin bottom-left) lies in the tile."""
        vx, vy, vw, vh = self.viewport
        return vx <= x < vx + vw and vy <= y < vy + vh


def grid_shape(count: int, width: float, height: float) -> tuple[int, int]:
    """(columns, rows) for ``count`` tiles in a ``width`` x ``height`` area.

    The shape whose tiles have the largest shorter side (ties: fewer empty
    cells), so tiles stay close to square whatever the view's aspect ratio.
    """
    if count < 1:
        raise ValueError(f"grid of {count} tiles: expected at least one")
    best, best_key = (1, count), None
    for columns in range(1, count + 1):
        rows = math.ceil(count / columns)
        side = min(width / columns, height / rows)
        key = (side, -(columns * rows - count))
        if best_key is None or key > best_key:
            best, best_key = (columns, rows), key
    return best


def tile_layout(
    names: list[str], viewport: tuple[int, int, int, int], fraction: float = 1.0
) -> list[Tile]:
    """The tiles of ``names`` in ``viewport`` (x, y, w, h; GL pixels), in reading order.

    Tile edges are rounded (not sizes), so tiles meet the gaps exactly; each
    tile is at least 1 x 1 pixel, and renders at ``fraction`` of its size
    (rounded, at least 1).
    """
    if not 0.0 < fraction <= 1.0:
        raise ValueError(f"tile fraction {fraction}: expected 0 < fraction <= 1")
    x0, y0, width, height = viewport
    columns, rows = grid_shape(len(names), width, height)
    tiles = []
    for index, name in enumerate(names):
        column, row = index % columns, index // columns
        left = x0 + round(column * width / columns) + (GAP // 2 if column else 0)
        right = x0 + round((column + 1) * width / columns) - (GAP - GAP // 2)
        top = round(row * height / rows) + (GAP // 2 if row else 0)
        bottom = round((row + 1) * height / rows) - (GAP - GAP // 2)
        if column == columns - 1:
            right = x0 + width
        if row == rows - 1:
            bottom = height
        w, h = max(right - left, 1), max(bottom - top, 1)
        size = (max(round(w * fraction), 1), max(round(h * fraction), 1))
        tiles.append(Tile(name, (left, y0 + height - top - h, w, h), size))
    return tiles


def tile_at(tiles: list[Tile], x: float, y: float) -> Tile | None:
    """The tile under GL pixel position (x, y) (origin bottom-left), or None (a gap)."""
    return next((tile for tile in tiles if tile.contains(x, y)), None)


class GridView:
    """Renders methods into tiles of one target, one :class:`FrameRenderer` per method.

    Parameters
    ----------
    renderer
        The window's renderer: its program cache and display settings are shared.
    """

    def __init__(self, renderer: FrameRenderer):
        self.ctx = renderer.ctx
        self.programs = renderer.programs
        self.display = renderer.display
        self.renderers: dict[str, FrameRenderer] = {}

    def renderer(self, name: str) -> FrameRenderer:
        """The renderer of method ``name``'s tile (made on first use)."""
        if name not in self.renderers:
            renderer = FrameRenderer(self.ctx, self.programs)
            self.renderers[name] = renderer
        self.renderers[name].display = self.display
        return self.renderers[name]

    def render(
        self,
        scene: GpuScene,
        methods: dict[str, Method],
        camera: OrbitCamera,
        tiles: list[Tile],
        target: moderngl.Framebuffer,
    ) -> tuple[dict[str, FrameStats], dict[str, str]]:
        """Render each tile's method at its render size into its viewport of ``target``.

        Methods that steer the camera (``pem`` snaps it to its baked path) do so
        before any tile is drawn, so every tile sees the same camera. A method that
        fails (a bad value, a bake for another scene, a shader this driver cannot
        compile) leaves its tile cleared and the others drawn.

        Returns
        -------
        stats : dict of str to FrameStats
            Each drawn tile's pass times (the display pass included).
        errors : dict of str to str
            The first line of each failed tile's error.
        """
        for tile in tiles:
            methods[tile.name].steer_camera(camera)
        stats, errors = {}, {}
        for tile in tiles:
            renderer = self.renderer(tile.name)
            try:
                stats[tile.name] = renderer.render(
                    scene, methods[tile.name], camera, tile.render_size, target, tile.viewport
                )
            except (UserError, ShaderCompileError) as exc:
                errors[tile.name] = str(exc).splitlines()[0]
                target.use()
                target.clear(0.0, 0.0, 0.0, 1.0, viewport=tile.viewport)
        for name in set(self.renderers) - {tile.name for tile in tiles}:
            self.renderers.pop(name).release()
        return stats, errors

    def release(self) -> None:
        """Free every tile renderer; safe to call twice."""
        for renderer in self.renderers.values():
            renderer.release()
        self.renderers.clear()
