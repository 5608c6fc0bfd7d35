"""The viewer's docked panels, drawn each frame: Method, Scene, Stats, Compare, Capture."""

from __future__ import annotations

from envstudio.engine.session import RenderSession
from envstudio.io.images import HDR_SUFFIXES
from envstudio.io.meshes import MESH_SUFFIXES
from envstudio.ui.capture_control import CaptureControl
from envstudio.ui.compare_panel import CompareState, compare_panel
from envstudio.ui.error_plot import GlossinessCurve, current_exponent
from envstudio.ui.file_dialogs import OpenFileDialog
from envstudio.ui.grid import GridState
from envstudio.ui.imgui_renderer import ImGuiRenderer
from envstudio.ui.jobs import DeferredWork
from envstudio.ui.method_choice import MethodChoice
from envstudio.ui.panels import (
    SceneDialogs,
    capture_panel,
    method_panel,
    scene_panel,
    stats_panel,
)
from envstudio.ui.scene_control import SceneControl
from envstudio.ui.stats import FrameHistory
from envstudio.ui.status import StatusLine


class ViewerPanels:
    """The panels and the Scene panel's "Open..." dialogs, whose files load as jobs.

    Parameters
    ----------
    session
        The scene and the display settings.
    control
        The scene, environment, mesh, rotation and turntable the Scene panel edits.
    choice
        The method on show (the Method panel picks another).
    compare, grid
        The split screen's and the grid's state (the Compare panel).
    history
        Frame times (the Stats panel).
    captures
        The Capture panel's options and requests.
    jobs
        Runs the file loads.
    status
        The status line.
    """

    def __init__(
        self,
        session: RenderSession,
        control: SceneControl,
        choice: MethodChoice,
        compare: CompareState,
        grid: GridState,
        history: FrameHistory,
        captures: CaptureControl,
        jobs: DeferredWork,
        status: StatusLine,
    ):
        self.session = session
        self.control = control
        self.choice = choice
        self.compare = compare
        self.grid = grid
        self.history = history
        self.captures = captures
        self.jobs = jobs
        self.status = status
        self.curve = GlossinessCurve()
        """The Compare panel's error-against-glossiness plot (its points taken by :meth:`step`)."""
        self.dialogs = SceneDialogs(
            OpenFileDialog("Open environment", "HDR environments", HDR_SUFFIXES),
            OpenFileDialog("Open mesh", "Meshes", MESH_SUFFIXES),
        )

    def draw(self, gui: ImGuiRenderer, render_size: tuple[int, int]) -> None:
        """Draw every panel; ``render_size`` is the 3D view's size in pixels (Stats)."""
        choice, display = self.choice, self.session.renderer.display
        picked = method_panel(
            choice.available,
            choice.method(choice.name),
            self.session.scene,
            self.status,
            gui,
            display,
        )
        if picked:
            choice.select(picked)
        scene_panel(self.control, display, self.dialogs, self.jobs, self.status)
        stats_panel(self.history, render_size)
        exponent = current_exponent(choice.method(choice.name), choice.hub())
        clicked = compare_panel(
            choice.available, choice.name, self.compare, self.grid, self.curve, exponent
        )
        if clicked and clicked != choice.name:
            choice.select(clicked)
        if capture_panel(self.captures.options):
            self.captures.request(self.captures.options.fmt)

    def step(self) -> None:
        """Start, restart or stop the glossiness plot's background measurement as the view
        changes and take the points it has sent (call at frame start; never waits)."""
        self.curve.update(self.session)

    def poll_dialogs(self) -> None:
        """Load the file an "Open..." dialog returned, as a job."""
        environment = self.dialogs.environment.poll()
        if environment:
            self.jobs.submit(
                f"loading {environment.name}", lambda: self.control.load_environment(environment)
            )
        mesh = self.dialogs.mesh.poll()
        if mesh:
            self.jobs.submit(f"loading {mesh.name}", lambda: self.control.load_mesh(mesh))

    def close(self) -> None:
        """Close any dialog still open; end the plot's measuring process."""
        self.dialogs.environment.close()
        self.dialogs.mesh.close()
        self.curve.release()
