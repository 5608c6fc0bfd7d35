"""The viewer's ImGui panels: Method, Scene, Stats and Capture.

Panels read and write the objects they are given and keep no copy of their
state. Work that blocks (loading files) is submitted to :class:`DeferredWork`
so the status line can say what is happening before it starts.

The panels are docked around the 3D view (:mod:`envstudio.ui.docking` builds the
default layout and keeps them off the view); afterwards ImGui's saved layout wins.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from imgui_bundle import imgui, implot

from envstudio.core.parameters import ParameterValues
from envstudio.engine.method import Method
from envstudio.engine.session import material_values
from envstudio.errors import UserError
from envstudio.scene.graph import Scene
from envstudio.ui.capture import FORMATS
from envstudio.ui.docking import PANEL_FLAGS
from envstudio.ui.file_dialogs import OpenFileDialog
from envstudio.ui.imgui_renderer import ImGuiRenderer
from envstudio.ui.jobs import DeferredWork
from envstudio.ui.parameter_widgets import parameter_widgets
from envstudio.ui.scene_control import SceneControl
from envstudio.ui.stats import FRAME_SERIES, FrameHistory
from envstudio.ui.status import StatusLine

SCENE_MESH = "scene's own"
"""Mesh picker entry bringing back the scene file's reflectors."""
LABEL_WIDTH = 110.0
"""Room kept right of the widgets for their labels."""


def _begin(name: str) -> bool:
    """Begin panel ``name`` (docked where the layout puts it); returns whether it is open."""
    expanded = imgui.begin(name, None, PANEL_FLAGS)[0]
    imgui.push_item_width(-LABEL_WIDTH)
    return expanded


def _end() -> None:
    imgui.pop_item_width()
    imgui.end()


def method_panel(
    methods: dict[str, type[Method]],
    method: Method,
    scene: Scene,
    status: StatusLine,
    gui: ImGuiRenderer | None = None,
    display: ParameterValues | None = None,
) -> str | None:
    """Method picker and the parameters of ``method``; returns a newly picked name or None.

    Parameters
    ----------
    methods
        The registered methods, in registration order (keys 1–9 pick the first nine).
    method
        The method shown now; its parameters are edited in place.
    scene
        The scene, whose first reflector's material "Reset" restores.
    status
        Receives rejected values.
    gui, display
        The ImGui renderer and the display settings: with both, a method's
        ``panel_figure`` section shows its ``panel_images`` (drawn only while open).
    """
    picked = None
    if _begin("Method"):
        picked = _method_combo(methods, method)
        imgui.text_wrapped(method.summary)
        imgui.separator()
        if list(method.values):
            parameter_widgets(method.values, status)
            if imgui.button("Reset"):
                _reset(method.values, scene)
            imgui.set_item_tooltip("Defaults, then the scene material's kd, fresnel, exponent.")
        else:
            imgui.text_disabled("no parameters")
        progress = method.status_line()
        if progress:
            imgui.separator()
            colour = (0.4, 0.9, 0.4, 1.0) if method.finished() else (1.0, 0.8, 0.3, 1.0)
            imgui.text_colored(colour, progress)
        fraction = method.progress()
        if fraction is not None:
            imgui.progress_bar(fraction, (-1.0, 0.0), f"{100 * fraction:.0f} %")
        if method.panel_figure and gui is not None and display is not None:
            _panel_figure(method, gui, display)
    _end()
    return picked


def _panel_figure(method: Method, gui: ImGuiRenderer, display: ParameterValues) -> None:
    """The method's ``panel_figure`` section: three images on the first row, the rest on the
    second (rsibr: the sources, then their warps and the generated map); labels as tooltips,
    the first three also as text."""
    if not imgui.collapsing_header(method.panel_figure):
        return
    images = method.panel_images(float(display["exposure"]), str(display["tonemap"]))
    if not images:
        imgui.text_disabled("after the first bake")
        return
    spacing = imgui.get_style().item_spacing.x
    edge = max((imgui.get_content_region_avail().x - 3 * spacing) / 4, 8.0)
    for index, (label, texture) in enumerate(images):
        if index not in (0, 3):
            imgui.same_line()
        imgui.image(gui.register_texture(texture), (edge, edge))
        imgui.set_item_tooltip(label)
    imgui.text_wrapped(", ".join(label for label, _ in images[:3]))


def _method_combo(methods: dict[str, type[Method]], method: Method) -> str | None:
    """The switch: "key: name — authors" per method, its summary as the tooltip; the name
    picked (None: the same)."""
    labels = {
        name: f"{i + 1}: " * (i < 9) + f"{name} — {cls.paper or cls.title}"
        for i, (name, cls) in enumerate(methods.items())
    }
    picked = None
    imgui.set_next_item_width(-1.0)
    if imgui.begin_combo("##method", labels[method.name]):
        for name, cls in methods.items():
            if imgui.selectable(labels[name], name == method.name)[0] and name != method.name:
                picked = name
            imgui.set_item_tooltip(cls.summary)
        imgui.end_combo()
    return picked


def _reset(values: ParameterValues, scene: Scene) -> None:
    for param in values:
        values[param.name] = param.default
    values.update(material_values(scene), ignore_unknown=True)


@dataclass
class SceneDialogs:
    """The Scene panel's two "Open..." dialogs."""

    environment: OpenFileDialog
    mesh: OpenFileDialog


def scene_panel(
    control: SceneControl,
    display: ParameterValues,
    dialogs: SceneDialogs,
    jobs: DeferredWork,
    status: StatusLine,
) -> None:
    """Scene, environment and mesh pickers, display settings, object rotation and turntable.

    The environment and mesh lists end with "Open file...", which shows the
    native dialog; files can also be dropped onto the window.
    """
    if _begin("Scene"):
        picked = _picker("scene", control.scene_label, control.scenes)
        if picked:
            jobs.submit(f"loading scene {picked}", lambda: control.load_scene(picked))
        picked = _picker(
            "environment",
            control.environment_label,
            control.environments,
            dialogs.environment,
            status,
        )
        if picked:
            path = control.environments[picked]
            jobs.submit(f"loading {picked}", lambda: control.load_environment(path))
        meshes = {SCENE_MESH: None, **control.meshes}
        picked = _picker("mesh", control.mesh_label, meshes, dialogs.mesh, status)
        if picked:
            path = meshes[picked]
            jobs.submit(f"loading {picked}", lambda: control.load_mesh(path))

        imgui.separator_text("Display")
        parameter_widgets(display, status)

        imgui.separator_text("Object")
        changed, rotation = imgui.slider_float3(
            "rotation", control.rotation, -180.0, 180.0, "%.0f°", imgui.SliderFlags_.always_clamp
        )
        imgui.set_item_tooltip("Rotation of the reflectors about X, Y, Z [deg]")
        if changed:
            control.set_rotation(rotation)
        _, control.turntable = imgui.checkbox("turntable", control.turntable)
        imgui.set_item_tooltip("Spin the reflectors about +Y")
        imgui.same_line()
        imgui.set_next_item_width(-1.0)
        _, control.turntable_speed = imgui.slider_float(
            "##speed", control.turntable_speed, -180.0, 180.0, "%.0f°/s"
        )
        imgui.set_item_tooltip("Turntable speed [deg/s]")
    _end()


def _picker(
    label: str,
    current: str,
    choices: dict[str, Path | None],
    dialog: OpenFileDialog | None = None,
    status: StatusLine | None = None,
) -> str | None:
    """A combo of ``choices`` showing ``current``; returns a newly picked name or None.

    With a ``dialog`` the list ends with "Open file...", which opens it (a
    failure to open goes to ``status``); it is greyed out while the dialog shows.
    """
    picked = None
    if imgui.begin_combo(label, current):
        for name in choices:
            if imgui.selectable(name, name == current)[0] and name != current:
                picked = name
        if dialog is not None:
            imgui.separator()
            waiting = imgui.SelectableFlags_.disabled if dialog.is_open else 0
            if imgui.selectable(f"Open file...##{label}", False, waiting)[0]:
                try:
                    dialog.open()
                except UserError as exc:
                    status.error(str(exc))
        imgui.end_combo()
    if dialog is not None:
        imgui.set_item_tooltip(f"Pick, open a file, or drop one onto the window ({label})")
    return picked


def stats_panel(history: FrameHistory, render_size: tuple[int, int]) -> None:
    """Frame time, each pass's time, and their history as a graph (same colours)."""
    if _begin("Stats"):
        clock = f", pass times by {history.clock}" if history.clock else ""
        imgui.text(f"{render_size[0]}x{render_size[1]}{clock}")
        latest = history.latest()
        column = max((imgui.calc_text_size(name).x for name in latest), default=0.0)
        for index, (name, ms) in enumerate(latest.items()):
            imgui.text_colored(implot.get_colormap_color(index), name)
            imgui.same_line(imgui.get_style().window_padding.x + column + 12.0)
            fps = f"  ({1e3 / ms:.0f} fps)" if name == FRAME_SERIES and ms > 0 else ""
            imgui.text(f"{ms:7.2f} ms{fps}")
        if implot.begin_plot("##history", (-1.0, -1.0), implot.Flags_.no_legend):
            implot.setup_axes(
                "", "ms", implot.AxisFlags_.no_tick_labels, implot.AxisFlags_.auto_fit
            )
            implot.setup_axis_limits(
                implot.ImAxis_.x1, 0.0, float(history.length), implot.Cond_.always
            )
            for name, values in history.series().items():
                implot.plot_line(name, values, 1.0, float(history.length - len(values)))
            implot.end_plot()
    _end()


@dataclass
class CaptureOptions:
    """What the Capture panel asks for.

    Attributes
    ----------
    folder : str
        Captures folder (the path field).
    fmt : str
        ``png`` (as displayed) or ``exr`` (linear HDR, before tone mapping).
    with_ui : bool
        PNG only: include the panels.
    """

    folder: str
    fmt: str = "png"
    with_ui: bool = False


def capture_panel(options: CaptureOptions) -> bool:
    """Capture settings; returns True when "Save" was pressed."""
    pressed = False
    if _begin("Capture"):
        _, options.folder = imgui.input_text("folder", options.folder)
        imgui.set_item_tooltip("Captures folder (created when needed)")
        for fmt in FORMATS:
            if imgui.radio_button(fmt.upper(), options.fmt == fmt):
                options.fmt = fmt
            imgui.same_line()
        imgui.begin_disabled(options.fmt == "exr")
        _, options.with_ui = imgui.checkbox("with UI", options.with_ui)
        imgui.end_disabled()
        imgui.set_item_tooltip("PNG only; EXR is the linear frame before tone mapping")
        pressed = imgui.button("Save capture")
        imgui.set_item_tooltip("F12 saves a PNG")
    _end()
    return pressed
