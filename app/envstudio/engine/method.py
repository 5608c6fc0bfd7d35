"""The renderer contract (DESIGN.md): a method, its declared parameters, its report sections,
and the session its hooks are handed.

A method draws the scene's reflectors into the bound HDR framebuffer (linear
radiance). It owns its GPU resources, prepares lazily (what depends on the
environment is rebuilt only when :attr:`GpuScene.environment_revision`
changes), times each pass with the frame's :class:`PassTimer`, and sets its
parameters as uniforms: a parameter change never recompiles unless the
parameter is declared ``rebuild=True``. An environment-map method looks the
environment up in ``frame.scene.static_environment()`` (seed 003's static EM:
the local objects drawn over the far field), not in ``GpuScene.cube``, and keys
what it derives from it on that object's ``revision``.

:class:`Session` is beside :class:`Method` because each names the other; the
session that drives methods (:mod:`envstudio.engine.session`) imports this module,
never the reverse.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar, Protocol

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.parameters import Parameter, ParameterValues
from envstudio.engine.frame import FrameRenderer
from envstudio.engine.frame_stats import FrameStats
from envstudio.gpu.programs import ProgramLibrary
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.graph import Scene
from envstudio.shading.gpu_scene import FrameInputs, GpuScene


@dataclass
class ReportExtra:
    """A section a method adds to ``envstudio compare``'s report (:meth:`Method.report_extras`).

    Attributes
    ----------
    title : str
        The section's heading.
    text : str
        A sentence or two above the table (plain text).
    columns : list of str
        The table's header (empty: no table).
    rows : list of list of str
        The table's cells, formatted.
    data : dict
        JSON-ready numbers behind the table, as compare.json gives them.
    images : list of (str, str)
        (file name in the report's folder, caption) of images the method wrote there.
    """

    title: str
    text: str
    columns: list[str] = field(default_factory=list)
    rows: list[list[str]] = field(default_factory=list)
    data: dict = field(default_factory=dict)
    images: list[tuple[str, str]] = field(default_factory=list)

    def to_json(self) -> dict:
        """JSON-ready: the title, text, table, data and image files."""
        return {
            "title": self.title,
            "text": self.text,
            "columns": list(self.columns),
            "rows": [list(row) for row in self.rows],
            "data": self.data,
            "images": [{"file": f, "caption": c} for f, c in self.images],
        }


class Method(ABC):
    """Base class of every renderer.

    Subclasses set :attr:`name`, :attr:`title`, :attr:`summary`, declare
    :attr:`parameters`, and implement :meth:`render`.

    Parameters
    ----------
    ctx
        Context the method renders with.
    programs
        Shared program cache of that context.
    """

    name: ClassVar[str]
    title: ClassVar[str]
    summary: ClassVar[str]
    parameters: ClassVar[tuple[Parameter, ...]] = ()
    #: The paper it implements, by its authors, as the seeds name them ("" for none).
    paper: ClassVar[str] = ""
    #: The reflectance model it renders: ``compare`` measures it against a reference of the
    #: same model (``phong``: diffuse + the Phong lobe with Schlick Fresnel; ``banks``;
    #: ``microfacet``); a model the ground truth cannot render gets no numbers.
    reflectance: ClassVar[str] = "phong"
    #: The image builds up over frames (a frame is one batch of an accumulation).
    progressive: ClassVar[bool] = False
    #: Title of a collapsing section of the Method panel showing :meth:`panel_images`
    #: ("" for none).
    panel_figure: ClassVar[str] = ""

    def __init__(self, ctx: moderngl.Context, programs: ProgramLibrary):
        self.ctx = ctx
        self.programs = programs
        self.values = ParameterValues(self.parameters)
        #: Work a progressive method may do per frame, in ms (None: a whole batch per
        #: frame, as headless commands want; the window sets a budget to stay responsive).
        self.frame_budget_ms: float | None = None

    @abstractmethod
    def render(self, frame: FrameInputs) -> None:
        """Draw every reflector of ``frame.scene`` into the bound framebuffer."""

    def prepare(self, scene: GpuScene) -> None:  # noqa: B027  (optional hook)
        """Load what the method needs before its first frame on ``scene`` (files, bakes).

        The viewer calls it when the method is picked and keeps the previous
        method on a :class:`~envstudio.errors.UserError`; :meth:`render` calls it
        too. Most methods need nothing.
        """

    def steer_camera(self, camera: OrbitCamera) -> None:  # noqa: B027  (optional hook)
        """Move the camera before a frame (``pem`` snaps it to its baked path); most do not."""

    def bench_notes(self) -> dict:
        """What ``envstudio bench`` reports beside this method's times (JSON-ready; none)."""
        return {}

    def finished(self) -> bool:
        """True when another frame would not change the image (progressive methods: converged)."""
        return True

    def status_line(self) -> str:
        """One line of progress for the UI and the CLI (empty for one-shot methods)."""
        return ""

    def missing_input(self) -> str | None:
        """Why the last frame is not the method's technique (a bake it needs), else None.

        A method that draws a stand-in where its input is missing says so here;
        ``envstudio atlas`` lists such cells with this reason instead of numbers.
        """
        return None

    def panel_images(self, exposure: float, tonemap: str) -> list[tuple[str, moderngl.Texture]]:
        """Labelled 8-bit images for the panel's :attr:`panel_figure` section (row 0 on top).

        Called only while that section is open, after the frame was drawn; ``exposure``
        and ``tonemap`` are the display's settings.
        """
        return []

    def progress(self) -> float | None:
        """Fraction done of background work the UI shows as a progress bar (None: none)."""
        return None

    def report_extras(self, session: Session, out_dir: Path) -> list[ReportExtra]:
        """Sections ``envstudio compare`` adds to its report for this method (none by default).

        Called once after the comparison was measured (its frames, metrics and
        parameters are kept: the method may change its values), with the session
        and the report's folder (made), where any image of a section is written.
        """
        return []

    def release(self) -> None:  # noqa: B027  (optional hook: most methods own nothing extra)
        """Free GPU resources the method owns; safe to call twice."""

    @classmethod
    def describe(cls) -> dict:
        """JSON-ready description: name, title, summary, parameters."""
        return {
            "name": cls.name,
            "title": cls.title,
            "summary": cls.summary,
            "paper": cls.paper,
            "reflectance": cls.reflectance,
            "parameters": [p.describe() for p in cls.parameters],
        }


class Session(Protocol):
    """What a method's hooks (report sections, figures, bench tables) may use of a session.

    :class:`envstudio.engine.session.RenderSession` is the one implementation:
    a scene on the GPU, its camera, the frame renderer and the methods' instances.
    """

    ctx: moderngl.Context
    programs: ProgramLibrary
    gpu_scene: GpuScene
    renderer: FrameRenderer
    camera: OrbitCamera

    @property
    def scene(self) -> Scene: ...

    def method(self, name: str) -> Method: ...

    def apply(self, method: Method, assignments: list[str]) -> None: ...

    def render_offscreen(self, method: str | Method, size: tuple[int, int]) -> FrameStats: ...

    def read_ldr(self) -> npt.NDArray[np.uint8]: ...

    def read_hdr(self) -> npt.NDArray[np.float32]: ...
