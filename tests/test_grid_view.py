"""The grid view's layout, hit-test, click and tile fraction (issue 29), without GL."""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.engine.grid_view import GAP, Tile, grid_shape, tile_at, tile_layout
from envstudio.ui.grid import (
    BUDGET_MS,
    WARM_UP_FRAMES,
    WINDOW_FRAMES,
    GridState,
    TileNumbers,
    TileScale,
    tile_label,
)

NAMES = ["mirror", "rsibr", "hwconv", "banks", "pem", "kautz", "parallax", "reference"]


@pytest.mark.parametrize(
    ("count", "size", "shape"),
    [
        (1, (800, 600), (1, 1)),
        (2, (800, 400), (2, 1)),
        (2, (400, 800), (1, 2)),
        (8, (1200, 600), (4, 2)),
        (9, (600, 600), (3, 3)),
        (3, (390, 579), (2, 2)),
    ],
)
def test_the_grid_keeps_its_tiles_large_and_near_square(count, size, shape):
    assert grid_shape(count, *size) == shape


@pytest.mark.parametrize("viewport", [(0, 0, 640, 480), (289, 0, 391, 579), (10, 20, 97, 33)])
def test_the_tiles_cover_the_viewport_apart_in_reading_order(viewport):
    tiles = tile_layout(NAMES, viewport)
    x0, y0, width, height = viewport
    covered = np.zeros((height, width), dtype=int)
    for tile in tiles:
        x, y, w, h = tile.viewport
        assert tile.render_size == (w, h)
        covered[y - y0 : y - y0 + h, x - x0 : x - x0 + w] += 1
    assert covered.max() == 1, "tiles overlap"
    columns, rows = grid_shape(len(NAMES), width, height)
    # only the gaps (and the cells past the last tile) are left uncovered
    empty = columns * rows - len(NAMES)
    assert covered.sum() >= width * height - GAP * (columns * height + rows * width) - (
        empty * (width // columns + 1) * (height // rows + 1)
    )
    # reading order: the first row is on top (GL rows count from the bottom)
    assert tiles[0].viewport[1] > tiles[columns].viewport[1]
    assert tiles[0].viewport[0] < tiles[1].viewport[0]


def test_tiles_render_at_their_fraction_and_hit_tests_find_them():
    tiles = tile_layout(["a", "b"], (100, 50, 400, 200), fraction=0.5)
    assert [t.render_size for t in tiles] == [(100, 100), (100, 100)]  # 199 and 200 wide
    assert tile_at(tiles, 150, 100).name == "a"
    assert tile_at(tiles, 499, 249).name == "b"
    assert tile_at(tiles, 299.5, 100) is None  # the gap
    assert tile_at(tiles, 99, 100) is None  # outside the view


def test_a_click_on_a_tile_names_it_a_drag_does_not():
    state = GridState()
    state.enter()
    # a 200 x 100 point window on a HiDPI screen: 400 x 200 framebuffer pixels
    state.tiles = tile_layout(["left", "right"], (0, 0, 400, 200))
    scale = (2.0, 2.0)
    assert state.click((150, 50), (151, 51), scale, 200) == "right"
    assert state.click((20, 90), (20, 90), scale, 200) == "left"
    assert state.click((20, 90), (60, 90), scale, 200) is None  # an orbit
    assert state.names(NAMES) == NAMES
    state.picked = ["kautz", "mirror"]
    assert state.names(NAMES) == ["mirror", "kautz"]


def test_the_fraction_drops_while_slow_and_comes_back_when_there_is_room():
    scale = TileScale()
    for _ in range(WARM_UP_FRAMES):  # compiling programs: not counted
        assert not scale.observe(5000.0)
    assert scale.fraction == 1.0 and scale.status() is None
    changes = [scale.observe(1.5 * BUDGET_MS) for _ in range(WINDOW_FRAMES)]
    assert changes == [False] * (WINDOW_FRAMES - 1) + [True]
    assert scale.fraction == 0.5
    for _ in range(40):  # the status line's time is smoothed over the frames
        scale.observe(0.9 * BUDGET_MS)  # a quarter of the pixels: 4x faster would not fit
    assert scale.fraction == 0.5
    assert scale.status() == f"grid at 1/2 size: {0.9 * BUDGET_MS:.0f} ms"  # smoothed
    for _ in range(WINDOW_FRAMES):
        scale.observe(0.1 * BUDGET_MS)
    assert scale.fraction == 1.0


def test_labels_say_method_ms_and_reference_numbers():
    tile = Tile("hwconv", (0, 0, 10, 10), (10, 10))
    assert tile_label(tile, None) == "hwconv"
    assert tile_label(tile, TileNumbers(ms=12.34)) == "hwconv  12.3 ms"
    numbers = TileNumbers(ms=3.0, psnr_db=24.56, flip=0.0812)
    assert tile_label(tile, numbers) == "hwconv  3.0 ms\nPSNR 24.6 dB  FLIP 0.081"
    assert tile_label(tile, TileNumbers(error="needs a bake")) == "hwconv: needs a bake"
