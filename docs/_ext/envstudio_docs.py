"""What the envmap-studio site builds from the code: technique pages, links into the
checkout, the gallery's image scraper and the EGL check.

- ``{envstudio-method} NAME``: a method's page body from the registry
  (``envstudio.engine.registry.available_methods()`` and the class's ``describe()``):
  its paper, summary, reflectance model, a parameter table, and its paragraph of
  ``docs/methods.md``.
- ``{envstudio-methods}``: the table of every registered method, linked to its page.
- ``{envstudio-scene-schema}``: the scene TOML schema, one table per TOML table, walked
  from the msgspec structs of ``envstudio.io.scene_file`` (:class:`SceneSpec` down): each
  key, the type it is checked against and its default.
- ``{checkout}`text <path>```: a link to a file of the checkout outside the site
  (``studies/``, ``examples/``), relative to the built page; a missing file is a warning.
- ``{checkout-figure} PATH``: a picture of the checkout outside the site (a study's figure) as
  a figure, copied into ``_generated/``; its content is the caption.
- :func:`scraper`: sphinx-gallery's custom image scraper, saving every image that
  ``envstudio.show`` displayed while a block ran (enlarged by whole pixels to at least
  :data:`MIN_WIDTH`: the gallery renders at 64×64 to stay fast).
- :func:`check_context`: one line and exit status 2 when no OpenGL context can be made,
  before the gallery runs; :func:`check_display`: the same when Xvfb is missing.
- The viewer tour (``docs/viewer.md``): :class:`ViewerTour` runs the real viewer once under
  a private Xvfb server (``_ext/viewer_tour.py``) while the gallery runs, and its
  screenshots land in ``_generated/viewer/``; ``{envstudio-viewer-shot} NAME`` shows one
  as a figure, its caption the directive's text and what the tour recorded (frame, time,
  the reference's status line).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import typing
from pathlib import Path

import numpy as np
from docutils import nodes
from docutils.statemachine import StringList
from sphinx.errors import ExtensionError
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

ROOT = Path(os.environ.get("ENVSTUDIO_CHECKOUT", Path(__file__).resolve().parents[2]))
LOGGER = logging.getLogger(__name__)

# ---------------------------------------------------------------- the EGL check


def check_context() -> None:
    """Exit with one line (status 2) when no headless OpenGL context can be made: the gallery
    renders through EGL, and a traceback per example says less than envstudio's own line."""
    from envstudio.errors import ContextError
    from envstudio.gpu.context import create_headless_context

    try:
        ctx = create_headless_context()
    except ContextError as error:
        sys.stderr.write(f"docs: the gallery needs OpenGL: {error}\n")
        sys.stderr.flush()
        os._exit(2)  # Sphinx would wrap a SystemExit from conf.py in a configuration error
    ctx.release()


def check_display() -> None:
    """Exit with one line (status 2) when the viewer tour cannot run: no Xvfb to run the
    viewer's window in."""
    if shutil.which("Xvfb") is None:
        sys.stderr.write("docs: the viewer tour needs Xvfb (Debian: apt install xvfb xauth)\n")
        sys.stderr.flush()
        os._exit(2)


# ---------------------------------------------------------------- the viewer tour

TOUR_SCRIPT = Path(__file__).with_name("viewer_tour.py")
TOUR_SETTINGS = {"window_size": [800, 500], "method_values": {"reference": {"trace": False}}}
"""The tour's settings file: a small window; the reference without tracing (the
environment-map model, as the grid's exact reference; a batch costs a third)."""
TOUR_TIMEOUT_S = 300


class ViewerTour:
    """The tour's run: a private Xvfb server and the viewer driven by ``viewer_tour.py``,
    started at ``builder-inited`` (before the gallery runs) and awaited before the pages
    are read."""

    def __init__(self):
        self.folder: tempfile.TemporaryDirectory | None = None
        self.server: subprocess.Popen | None = None
        self.viewer: subprocess.Popen | None = None
        self.out: Path | None = None

    def start(self, app) -> None:
        """Start Xvfb and the viewer; the screenshots go to ``_generated/viewer/``."""
        self.out = Path(app.srcdir) / "_generated" / "viewer"
        shutil.rmtree(self.out, ignore_errors=True)
        self.folder = tempfile.TemporaryDirectory(prefix="envstudio-tour-")
        home = Path(self.folder.name)
        (home / "config").mkdir()
        (home / "config" / "settings.json").write_text(json.dumps(TOUR_SETTINGS))
        read_fd, write_fd = os.pipe()
        self.server = subprocess.Popen(
            [
                *("Xvfb", "-displayfd", str(write_fd)),
                *("-screen", "0", "1280x800x24", "-nolisten", "tcp"),
            ],
            pass_fds=(write_fd,),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        os.close(write_fd)
        with os.fdopen(read_fd) as pipe:
            number = pipe.readline().strip()
        if not number:
            self.stop()
            raise ExtensionError("viewer tour: Xvfb exited before reporting its display")
        env = dict(os.environ, DISPLAY=f":{number}", ENVSTUDIO_CONFIG_DIR=str(home / "config"))
        env["XDG_PICTURES_DIR"] = str(home / "Pictures")
        env.pop("WAYLAND_DISPLAY", None)
        self.viewer = subprocess.Popen(
            [sys.executable, str(TOUR_SCRIPT), str(self.out)],
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )

    def wait(self, app=None, env=None, docnames=None) -> None:
        """Wait for the viewer (once); a failure stops the build with its last line."""
        if self.viewer is None:
            return
        try:
            output, _ = self.viewer.communicate(timeout=TOUR_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            self.viewer.kill()
            output, _ = self.viewer.communicate()
        status, self.viewer = self.viewer.returncode, None
        self.stop()
        if status != 0:
            lines = [line for line in output.splitlines() if line.strip()] or ["no output"]
            said = [line for line in lines if line.startswith("envstudio:")] or lines
            raise ExtensionError(f"viewer tour: the viewer exited with {status}: {said[-1]}")
        LOGGER.info("viewer tour: %s", ", ".join(sorted(p.name for p in self.out.glob("*.png"))))

    def stop(self, *_args) -> None:
        """End the viewer (if still running) and the server; remove the settings folder."""
        if self.viewer is not None:
            self.viewer.kill()
            self.viewer.wait()
            self.viewer = None
        if self.server is not None:
            self.server.terminate()
            try:
                self.server.wait(5)
            except subprocess.TimeoutExpired:
                self.server.kill()
                self.server.wait()
            self.server = None
        if self.folder is not None:
            self.folder.cleanup()
            self.folder = None

    def record(self) -> dict:
        """What the tour wrote in ``tour.json``: per shot its frame, seconds, method, status."""
        return json.loads((self.out / "tour.json").read_text(encoding="utf-8"))


TOUR = ViewerTour()


def _shot_facts(name: str, record: dict) -> str:
    """The generated line of a shot's caption: when the tour took it (frame, seconds since the
    first frame, the picture's size); for the reference's views, its status line then."""
    if name == "reference":
        views = [record[shot] for shot in sorted(record) if shot.startswith("reference-")]
        said = "; ".join(
            f"frame {facts['frame']}, {facts['seconds']:g} s: “{facts['status']}”"
            for facts in views
        )
        return f"Left to right, with the Method panel's status line: {said}."
    if name == "capture-file":
        return f"The file F12 wrote, `{record['capture']['file']}`."
    facts = record[name]
    width, height = facts["size"]
    return (
        f"Frame {facts['frame']}, {facts['seconds']:g} s after the first; {width}×{height} pixels."
    )


# ---------------------------------------------------------------- the gallery scraper

_SHOWN: list = []
MIN_WIDTH = 384  # shown images narrower than this are enlarged by whole pixels


def _record_show() -> None:
    """Wrap ``envstudio.api.show`` so that what it returns is remembered for the scraper."""
    from envstudio import api

    if getattr(api.show, "_recorded", False):
        return
    show = api.show

    def recorded_show(*args, **kwargs):
        image = show(*args, **kwargs)
        _SHOWN.append(image)
        return image

    recorded_show.__doc__ = show.__doc__
    recorded_show._recorded = True
    api.show = recorded_show


def reset_shown(gallery_conf, fname) -> None:
    """sphinx-gallery's ``reset_modules`` hook: forget images left by an earlier example."""
    _record_show()
    _SHOWN.clear()


def scraper(block, block_vars, gallery_conf) -> str:
    """sphinx-gallery's custom image scraper: save what ``es.show`` displayed in this block as
    PNGs at the paths sphinx-gallery hands out, and return their reST."""
    from PIL import Image
    from sphinx_gallery.scrapers import figure_rst

    paths = []
    iterator = block_vars["image_path_iterator"]
    for shown in _SHOWN:
        path = next(iterator)
        picture = Image.fromarray(np.ascontiguousarray(shown.pixels))
        scale = max(1, -(-MIN_WIDTH // picture.width))  # the gallery renders tiny frames
        if scale > 1:
            picture = picture.resize(
                (picture.width * scale, picture.height * scale), Image.Resampling.NEAREST
            )
        picture.save(path)
        paths.append(path)
    _SHOWN.clear()
    return figure_rst(paths, gallery_conf["src_dir"])


# ---------------------------------------------------------------- links into the checkout


def checkout_role(name, rawtext, text, lineno, inliner, options=None, content=None):
    """``{checkout}`label <path>```: the checkout's file ``path`` (relative to its root),
    linked relative to the built page so the link works in the local build."""
    match = re.fullmatch(r"\s*(.*?)\s*<([^>]+)>\s*", text, re.S)
    label, target = (match.group(1), match.group(2)) if match else (text, text)
    path, _, anchor = target.partition("#")
    env = inliner.document.settings.env
    messages = []
    if not (ROOT / path).exists():
        messages.append(inliner.reporter.warning(f"checkout file not found: {path}", line=lineno))
    page_dir = Path(env.app.outdir) / Path(env.docname).parent
    uri = os.path.relpath(ROOT / path, page_dir).replace(os.sep, "/")
    if (ROOT / path).is_dir():
        uri += "/"
    if anchor:
        uri += "#" + anchor
    node = nodes.reference(rawtext, label or path, refuri=uri)
    return [node], messages


_OUTSIDE_LINK = re.compile(r"\[([^\]]+)\]\(\.\./((?:studies|examples)/[^)\s]*)\)")


def outside_links(markdown: str) -> str:
    """Markdown links from ``docs/`` to ``../studies`` and ``../examples`` as ``{checkout}``
    roles (MyST would look for them among the site's pages)."""
    return _OUTSIDE_LINK.sub(
        lambda m: f"{{checkout}}`{m.group(1).strip('`')} <{m.group(2)}>`", markdown
    )


def rewrite_outside_links(app, docname, source) -> None:
    """``source-read``: rewrite the links of the kept Markdown files (plugins.md)."""
    source[0] = outside_links(source[0])


class CheckoutFigureDirective(SphinxDirective):
    """``{checkout-figure} PATH``: the checkout's image PATH (relative to its root) as a figure,
    copied into the sources' ``_generated/`` (the sources may be a copy of ``docs/`` elsewhere);
    ``:alt:`` and ``:width:`` as the figure's; the content is the caption."""

    required_arguments = 1
    has_content = True
    option_spec: typing.ClassVar[dict] = {"alt": str, "width": str}

    def run(self):
        path = self.arguments[0]
        source = ROOT / path
        if not source.is_file():
            raise self.error(f"checkout-figure: no file {path} in the checkout")
        target = Path(self.env.srcdir) / "_generated" / path
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(source, target)
        self.env.note_dependency(str(source))
        lines = [f"```{{figure}} /_generated/{path}"]
        lines += [f":{name}: {value}" for name, value in self.options.items()]
        lines += ["", *self.content, "```"]
        container = nodes.container()
        self.state.nested_parse(StringList(lines, source=self.env.docname), 0, container)
        return container.children


# ---------------------------------------------------------------- technique pages


def _methods():
    from envstudio.engine.registry import available_methods

    return available_methods()


def method_paragraphs() -> dict[str, str]:
    """Each method's hand-written paragraph: its row of docs/methods.md's table."""
    rows = {}
    text = (ROOT / "docs" / "methods.md").read_text(encoding="utf-8")
    for line in text.splitlines():
        match = re.match(r"\| `([a-z0-9_]+)` \| (.*) \|$", line)
        if match:
            rows[match.group(1)] = outside_links(match.group(2))
    return rows


def _cell(value: object) -> str:
    text = str(value).replace("|", "\\|").replace("\n", " ")
    return text.replace("<", "\\<").replace("*", "\\*")


def _range(parameter: dict) -> str:
    if parameter.get("choices"):
        return ", ".join(f"`{c}`" for c in parameter["choices"])
    if parameter["kind"] == "bool":
        return "on / off"
    if parameter["kind"] == "path":
        suffixes = parameter.get("suffixes") or ()
        return "a file " + ", ".join(f"`{s}`" for s in suffixes) if suffixes else "a file"
    low, high = parameter.get("minimum"), parameter.get("maximum")
    if low is None and high is None:
        return ""
    return f"{low:g} … {high:g}" if low is not None and high is not None else ""


def _default(parameter: dict) -> str:
    value = parameter["default"]
    if isinstance(value, list):
        return ", ".join(f"{v:g}" for v in value)
    if value == "":
        return "(none)"
    return f"{value:g}" if isinstance(value, float) else str(value)


# the shipped scene that shows a method best (default studio), and what its picture needs
PICTURE_SCENES = {"banks": "brushed", "pem": "room", "parallax": "room"}
PICTURE_PARAMETERS = {"pem": {"coverage": "file"}, "reference": {"max_samples": 128}}
PICTURE_SIZE = (128, 128)


def picture_command(name: str) -> str:
    """The ``envstudio render`` command that draws a technique page's picture."""
    scene = PICTURE_SCENES.get(name, "studio")
    params = "".join(f" --param {k}={v}" for k, v in PICTURE_PARAMETERS.get(name, {}).items())
    size = "x".join(str(n) for n in PICTURE_SIZE)
    return f"envstudio render --scene {scene} --method {name}{params} --size {size} -o {name}.png"


def render_picture(name: str, srcdir: Path) -> str:
    """Render the technique page's picture through the Python API into the sources'
    ``_generated/`` folder; its path for the image directive (relative to the sources)."""
    from PIL import Image

    import envstudio as es

    scene = es.load_scene(PICTURE_SCENES.get(name, "studio"))
    with contextlib.redirect_stderr(io.StringIO()):  # the reference's progress line
        frame = es.render(scene, name, size=PICTURE_SIZE, **PICTURE_PARAMETERS.get(name, {}))
    path = srcdir / "_generated" / "techniques" / f"{name}.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(es.display(frame)).save(path)
    return f"/_generated/techniques/{name}.png"


def method_markdown(name: str, picture: str | None = None) -> list[str]:
    """The generated part of a technique page, as MyST Markdown lines."""
    cls = _methods()[name]
    described = cls.describe()
    paragraph = method_paragraphs().get(name)
    lines = [f"**{described['summary']}**", ""]
    if picture:
        lines += [f"```{{image}} {picture}", f":alt: {name}", "```", ""]
    lines += [
        "| | |",
        "| --- | --- |",
        f"| paper | {_cell(described['paper'])} |",
        f"| reflectance model | `{described['reflectance']}` |",
        f"| the picture above | `{picture_command(name)}` |",
        "",
    ]
    if paragraph:
        lines += ["## In detail", "", paragraph, ""]
    lines += [
        "## Parameters",
        "",
        "Set with `--param NAME=VALUE` on the command line, or as keyword arguments of "
        "`es.render`; generated from the method's declarations (`envstudio methods`).",
        "",
        "| parameter | kind | range | default | unit | what it does |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for p in described["parameters"]:
        lines.append(
            f"| `{p['name']}` | {p['kind']} | {_cell(_range(p))} | {_cell(_default(p))} "
            f"| {_cell(p.get('unit', ''))} | {_cell(p.get('help', ''))} |"
        )
    return lines


class _MarkdownDirective(SphinxDirective):
    """Parse generated MyST lines into the page at the directive."""

    def parse(self, lines: list[str]) -> list[nodes.Node]:
        container = nodes.container()
        self.state.nested_parse(StringList(lines, source=self.env.docname), 0, container)
        return container.children


class MethodDirective(_MarkdownDirective):
    """``{envstudio-method} NAME``: the registry's description of one method."""

    required_arguments = 1

    def run(self):
        name = self.arguments[0]
        if name not in _methods():
            raise self.error(f"envstudio-method: no registered method {name!r}")
        picture = render_picture(name, Path(self.env.srcdir))
        return self.parse(method_markdown(name, picture))


class MethodsDirective(_MarkdownDirective):
    """``{envstudio-methods}``: every registered method, linked to its page."""

    def run(self):
        lines = ["| method | paper | reflectance | what it does |", "| --- | --- | --- | --- |"]
        for name, cls in _methods().items():
            d = cls.describe()
            lines.append(
                f"| {{doc}}`{_cell(d['title'])} </techniques/{name}>` | {_cell(d['paper'])} "
                f"| `{d['reflectance']}` | {_cell(d['summary'])} |"
            )
        return self.parse(lines)


class ViewerShotDirective(_MarkdownDirective):
    """``{envstudio-viewer-shot} NAME``: the tour's screenshot NAME as a figure; its caption
    the directive's content, then :func:`_shot_facts`."""

    required_arguments = 1
    has_content = True

    def run(self):
        name = self.arguments[0]
        if not (TOUR.out / f"{name}.png").is_file():
            raise self.error(f"envstudio-viewer-shot: the tour took no shot {name!r}")
        self.env.note_dependency(str(TOUR.out / "tour.json"))
        lines = [f"```{{figure}} /_generated/viewer/{name}.png", f":alt: {name}", ""]
        lines += [*self.content, "", f"*{_shot_facts(name, TOUR.record())}*", "```"]
        return self.parse(lines)


# ---------------------------------------------------------------- the scene file schema


def _struct_of(tp):
    """The msgspec struct a field's type declares (plain, optional or a list of them)."""
    import msgspec

    from envstudio.io import scene_file

    tp = scene_file._plain(tp)
    if typing.get_origin(tp) is list:
        tp = scene_file._plain(typing.get_args(tp)[0])
    return tp if isinstance(tp, type) and issubclass(tp, msgspec.Struct) else None


def _toml_default(field) -> str:
    """A struct field's default as TOML would spell it ("required" where it has none)."""
    import msgspec

    if field.default is not msgspec.NODEFAULT:
        value = field.default
    elif field.default_factory is not msgspec.NODEFAULT:
        return "(the table's defaults)"
    else:
        return "**required**"
    if value is None:
        return "(none)"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, str):
        return f'`"{value}"`'
    if isinstance(value, (tuple, list)):
        return "`[" + ", ".join(f"{v:g}" for v in value) + "]`"
    return f"`{value:g}`" if isinstance(value, float) else f"`{value}`"


def _toml_type(tp) -> str:
    """What a key's value must be, in words, as the scene loader's messages say it."""
    from envstudio.io import scene_file

    args = typing.get_args(tp)
    optional = type(None) in args and len(args) == 2
    words = scene_file._describe(tp, "a value")
    return _cell(words + (" (optional)" if optional else ""))


def scene_schema(spec=None, table: str = "", array: bool = False) -> list[tuple[str, str, list]]:
    """``(header, docstring, rows)`` per TOML table below ``spec`` (default ``SceneSpec``),
    each row ``(key, type, default)``; sub-tables follow their parent."""
    import msgspec

    from envstudio.io import scene_file

    spec = spec or scene_file.SceneSpec
    header = f"[[{table}]]" if array else f"[{table}]" if table else "top level"
    rows, below = [], []
    for field in msgspec.structs.fields(spec):
        struct = _struct_of(field.type)
        path = f"{table}.{field.name}" if table else field.name
        if struct is not None:
            listed = typing.get_origin(scene_file._plain(field.type)) is list
            name = f"[[{path}]]" if listed else f"[{path}]"
            rows.append((field.name, f"table `{name}`", _toml_default(field)))
            below += scene_schema(struct, path, listed)
        else:
            rows.append((field.name, _toml_type(field.type), _toml_default(field)))
    doc = " ".join((spec.__doc__ or "").strip().split("\n\n")[0].split())
    doc = re.sub(r"^``\[[^`]*\]``: ", "", doc)  # the header, shown above it already
    doc = doc[:1].upper() + doc[1:]
    return [(header, doc, rows), *below]


class SceneSchemaDirective(_MarkdownDirective):
    """``{envstudio-scene-schema}``: the scene TOML schema from the msgspec structs."""

    def run(self):
        lines = []
        for header, doc, rows in scene_schema():
            lines += [f"### `{header}`" if header != "top level" else "### Top level", ""]
            if doc:
                lines += [doc, ""]
            lines += ["| key | type | default |", "| --- | --- | --- |"]
            lines += [f"| `{key}` | {kind} | {default} |" for key, kind, default in rows]
            lines.append("")
        return self.parse(lines)


def setup(app):
    app.add_role("checkout", checkout_role)
    app.add_directive("envstudio-method", MethodDirective)
    app.add_directive("envstudio-methods", MethodsDirective)
    app.add_directive("envstudio-scene-schema", SceneSchemaDirective)
    app.add_directive("envstudio-viewer-shot", ViewerShotDirective)
    app.add_directive("checkout-figure", CheckoutFigureDirective)
    app.connect("builder-inited", TOUR.start, priority=100)  # before the gallery runs
    app.connect("env-before-read-docs", TOUR.wait)
    app.connect("build-finished", TOUR.stop)
    app.connect("source-read", rewrite_outside_links)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
