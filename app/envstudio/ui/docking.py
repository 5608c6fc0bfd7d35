"""The viewer's docked layout: the 3D view is the dock space's central node, the panels are
docked around it, never over it.

Default layout (first run, and View > Reset layout), at 1280x800 points::

    +------------------------------------------------------------+
    | View                                            (menu bar) |
    +------------+------------------------------+----------------+
    | Method     |                              | Compare        |
    |            |                              |                |
    |            |          3D view             |                |
    |            |       (central node)         +----------------+
    +------------+                              | Stats | Capture|
    | Scene      |                              |   (tabs)       |
    |            |                              |                |
    +------------+------------------------------+----------------+

The dock space covers the main viewport's work area (below the menu bar) with a
pass-through central node: ImGui draws nothing there and lets the mouse through,
so the camera gets the presses. :meth:`DockLayout.frame` returns that node's
rectangle in points; :func:`gl_viewport` turns it into framebuffer pixels
(origin bottom-left) for the renderer, whose render size, and so the camera's
aspect ratio, is the rectangle's. With the panels hidden (Tab) the dock space is
kept alive but not shown, and the view is the whole window.

ImGui saves the layout (dock nodes, which panel is where) in its ini text, which
the viewer keeps in its settings file (:mod:`envstudio.ui.settings`, written
atomically), so it persists between runs.

ImGui applies a layout one frame late in two cases: the dock space's first
frame (its host window is new) and the frame after the menu bar reappears (the
work area moves below it a frame later). :meth:`DockLayout.warm_up` runs the
first one before the viewer's first frame, without drawing; the second shows
the view for one frame reaching under the menu bar.
"""

from __future__ import annotations

from dataclasses import dataclass

from imgui_bundle import imgui
from imgui_bundle.imgui import internal

DOCK_SPACE_ID = 0x45535444
"""ID of the dock space (any fixed non-zero value: ImGui saves the layout under it)."""
LEFT = ("Method", "Scene")
"""The left column, top to bottom."""
RIGHT_TOP = "Compare"
RIGHT_TABS = ("Stats", "Capture")
"""Sharing one tabbed node below Compare (Stats shown first)."""
PANELS = (*LEFT, RIGHT_TOP, *RIGHT_TABS)
"""Every panel the viewer docks: their ImGui window names."""
PANEL_FLAGS = imgui.WindowFlags_.no_focus_on_appearing
"""Flags of every panel's ``imgui.begin``: a panel that appears (each at start, all of them
after Tab) does not come to the front, so a tabbed node keeps the tab it had on show."""
LEFT_WIDTH = 300.0
RIGHT_WIDTH = 280.0
"""Default column widths in points, at most :data:`MAX_COLUMN_SHARE` of the window each."""
MAX_COLUMN_SHARE = 0.3
METHOD_SHARE = 0.6
"""Share of the left column's height taken by Method (Scene below)."""
COMPARE_SHARE = 0.5
"""Share of the right column's height taken by Compare (Stats and Capture below): at 1280x800
its settings, the glossiness curve's button and its 220-point plot fit without scrolling
(at a quarter the plot was cut off)."""


@dataclass(frozen=True)
class ViewRect:
    """A rectangle in ImGui display coordinates: points, origin top-left."""

    x: float
    y: float
    width: float
    height: float

    @property
    def aspect(self) -> float:
        """Width over height (1 for an empty rectangle)."""
        return self.width / self.height if self.height > 0 else 1.0

    def contains(self, x: float, y: float) -> bool:
        """Whether the point (x, y) lies inside."""
        return self.x <= x < self.x + self.width and self.y <= y < self.y + self.height

    def overlaps(self, other: ViewRect) -> bool:
        """Whether the two rectangles share any area."""
        return (
            self.x < other.x + other.width
            and other.x < self.x + self.width
            and self.y < other.y + other.height
            and other.y < self.y + self.height
        )


def gl_viewport(
    rect: ViewRect, window_size: tuple[int, int], buffer_size: tuple[int, int]
) -> tuple[int, int, int, int]:
    """``rect`` (points, origin top-left) as a GL viewport (x, y, w, h) in framebuffer pixels,
    origin bottom-left, clipped to the framebuffer.

    Edges are rounded, not sizes, so rectangles that meet in points meet in pixels; on a
    HiDPI screen (framebuffer larger than the window) each point is several pixels.
    """
    scale_x = buffer_size[0] / window_size[0] if window_size[0] > 0 else 1.0
    scale_y = buffer_size[1] / window_size[1] if window_size[1] > 0 else 1.0
    left = min(max(round(rect.x * scale_x), 0), buffer_size[0])
    right = min(max(round((rect.x + rect.width) * scale_x), left), buffer_size[0])
    top = min(max(round(rect.y * scale_y), 0), buffer_size[1])
    bottom = min(max(round((rect.y + rect.height) * scale_y), top), buffer_size[1])
    return left, buffer_size[1] - bottom, right - left, bottom - top


def pixel_scale(window_size: tuple[int, int], buffer_size: tuple[int, int]) -> tuple[float, float]:
    """Framebuffer pixels per window point (x, y); 1 along an empty side."""
    (w, h), (bw, bh) = window_size, buffer_size
    return (bw / w if w else 1.0, bh / h if h else 1.0)


class DockLayout:
    """The dock space, its default layout, and the View menu.

    Call :meth:`frame` once per ImGui frame, after ``imgui.new_frame()`` and before
    the panels (``imgui.begin(name)`` with a name of :data:`PANELS`).

    Attributes
    ----------
    toggle_panels : bool
        View > Hide panels was chosen this frame (the viewer hides them, as Tab does).
    """

    def __init__(self):
        self._reset = False
        self.toggle_panels = False

    def reset(self) -> None:
        """Restore the default layout in the next frame (View > Reset layout)."""
        self._reset = True

    def warm_up(self) -> None:
        """One frame that is never drawn: the dock space's host window and the panels'
        windows are made, so the first drawn frame has its final layout. Call it
        where :meth:`frame` would be called, then ``imgui.end_frame()``."""
        self.frame(True)
        for name in PANELS:
            imgui.begin(name, None, PANEL_FLAGS)
            imgui.end()
        self.toggle_panels = False

    def frame(self, panels_shown: bool) -> ViewRect:
        """Menu bar and dock space for this frame; returns the 3D view's rectangle.

        Parameters
        ----------
        panels_shown
            False: no menu bar, the dock space kept alive but hidden, the view is
            the whole display.
        """
        self.toggle_panels = False
        if panels_shown:
            self._menu_bar()
        viewport = imgui.get_main_viewport()
        if self._reset or internal.dock_builder_get_node(DOCK_SPACE_ID) is None:
            build_default_layout(
                DOCK_SPACE_ID,
                (viewport.work_pos.x, viewport.work_pos.y),
                (viewport.work_size.x, viewport.work_size.y),
            )
            self._reset = False
            imgui.set_window_focus(RIGHT_TABS[0])  # the first tab on show (if it exists)
        flags = imgui.DockNodeFlags_.passthru_central_node
        if not panels_shown:
            flags |= imgui.DockNodeFlags_.keep_alive_only
        imgui.dock_space_over_viewport(DOCK_SPACE_ID, viewport, flags)
        if not panels_shown:
            return ViewRect(viewport.pos.x, viewport.pos.y, viewport.size.x, viewport.size.y)
        return central_rect()

    def _menu_bar(self) -> None:
        if not imgui.begin_main_menu_bar():
            return
        if imgui.begin_menu("View"):
            if imgui.menu_item("Reset layout", "", False)[0]:
                self.reset()
            imgui.set_item_tooltip("Dock the panels where they were on the first run.")
            if imgui.menu_item("Hide panels", "Tab", False)[0]:
                self.toggle_panels = True
            imgui.end_menu()
        imgui.end_main_menu_bar()


def central_rect() -> ViewRect:
    """The central node of the dock space: where the 3D view is drawn."""
    node = internal.dock_builder_get_central_node(DOCK_SPACE_ID)
    return ViewRect(node.pos.x, node.pos.y, node.size.x, node.size.y)


def build_default_layout(dock_id: int, pos: tuple[float, float], size: tuple[float, float]) -> None:
    """(Re)build dock space ``dock_id`` over ``pos``, ``size`` with the default layout (the
    module's picture), docking every panel of :data:`PANELS`; inside an ImGui frame."""
    width = max(size[0], 1.0)
    internal.dock_builder_remove_node(dock_id)
    internal.dock_builder_add_node(
        dock_id,
        imgui.DockNodeFlags_.passthru_central_node | internal.DockNodeFlagsPrivate_.dock_space,
    )
    internal.dock_builder_set_node_pos(dock_id, pos)
    internal.dock_builder_set_node_size(dock_id, size)
    left_share = min(LEFT_WIDTH / width, MAX_COLUMN_SHARE)
    right_width = min(RIGHT_WIDTH, MAX_COLUMN_SHARE * width)
    split = internal.dock_builder_split_node(dock_id, imgui.Dir.left, left_share)
    left, rest = split.id_at_dir, split.id_at_opposite_dir
    split = internal.dock_builder_split_node(
        rest, imgui.Dir.right, right_width / (width * (1.0 - left_share))
    )
    right = split.id_at_dir
    split = internal.dock_builder_split_node(left, imgui.Dir.up, METHOD_SHARE)
    internal.dock_builder_dock_window(LEFT[0], split.id_at_dir)
    internal.dock_builder_dock_window(LEFT[1], split.id_at_opposite_dir)
    split = internal.dock_builder_split_node(right, imgui.Dir.up, COMPARE_SHARE)
    internal.dock_builder_dock_window(RIGHT_TOP, split.id_at_dir)
    for name in RIGHT_TABS:
        internal.dock_builder_dock_window(name, split.id_at_opposite_dir)
    internal.dock_builder_finish(dock_id)
