"""``envstudio doctor``: what this machine has for envstudio, and what is missing.

Prints the GL renderer and version reached through EGL (and whether compute
shaders are there, naming what needs them), the EGL and window backends found,
the Python and package versions, the cache and config folders with their sizes,
and one line per missing piece with the exact command that fixes it. Exit status
0 when nothing is missing, 1 otherwise.

Every probe runs inside ``try``: a machine without GL, without a display or with
a broken package gets a line here, never a traceback. This module imports only
the standard library at the top, so that it still runs when a dependency is
missing (``envstudio.cli`` dispatches here before importing the commands).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import platform
import re
import shutil
import sys
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path

DISTRIBUTION = "envmap-studio"
EGL_PACKAGES = "libegl1 libegl-mesa0 libgl1-mesa-dri"
LIBGL_PACKAGES = "libgl1"
LIBEGL_OVERRIDE = "GLCONTEXT_LINUX_LIBEGL"  # glcontext's own variable, honoured by gpu/context.py
LIBGL_OVERRIDE = "GLCONTEXT_LINUX_LIBGL"
DEFAULT_EGL_VENDOR_DIRS = ("/etc/glvnd/egl_vendor.d", "/usr/share/glvnd/egl_vendor.d")

# What needs OpenGL 4.3 (compute shaders, image load/store, storage buffers); see the
# require_version / has_compute calls in methods/ and envmap/.
NEEDS_COMPUTE = (
    ("reference", "the whole method (storage buffers); unavailable below 4.3"),
    ("kautz", "dynamic=true and cross_face_filter=true"),
    ("banks", "builder=gpu; below 4.3 the 3D map is built with NumPy"),
)


@dataclass
class Report:
    """The lines printed and the problems found (each with its fix)."""

    lines: list[str] = field(default_factory=list)
    problems: list[tuple[str, str]] = field(default_factory=list)

    def section(self, title: str) -> None:
        self.lines.append("")
        self.lines.append(title)

    def item(self, name: str, value: str) -> None:
        self.lines.append(f"  {name:<18} {value}")

    def missing(self, what: str, fix: str) -> None:
        self.problems.append((what, fix))


def _root_prefix() -> str:
    return "" if hasattr(os, "geteuid") and os.geteuid() == 0 else "sudo "


def _apt(packages: str) -> str:
    return f"{_root_prefix()}apt-get install --no-install-recommends {packages}"


def _pip(spec: str) -> str:
    if getattr(sys, "frozen", False):  # the PyInstaller bundle: no pip, its packages are inside
        return "unpack the bundle again (or rebuild it: python packaging/build_bundle.py)"
    return f"{sys.executable} -m pip install '{spec}'"


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def _folder_size(folder: Path) -> tuple[int, int]:
    """Bytes and files under ``folder`` (0, 0 when it does not exist)."""
    total = files = 0
    for base, _dirs, names in os.walk(folder):
        for name in names:
            try:
                total += (Path(base) / name).stat().st_size
                files += 1
            except OSError:
                pass
    return total, files


def _human(size: int) -> str:
    for unit in ("B", "KB", "MB", "GB"):
        if size < 1024 or unit == "GB":
            return f"{size:.0f} {unit}" if unit == "B" else f"{size:.1f} {unit}"
        size /= 1024
    return f"{size} B"


def _version() -> str:
    try:
        return metadata.version(DISTRIBUTION)
    except metadata.PackageNotFoundError:
        return "unknown (not installed: pip install -e .)"


# -- GL -----------------------------------------------------------------------------------------


def _library(report: Report, label: str, override: str, name: str, packages: str) -> str | None:
    """Find and load libEGL / libGL the way glcontext does; report it. Returns the path."""
    forced = os.environ.get(override)
    path = forced or ctypes.util.find_library(name)
    source = f" (from ${override})" if forced else ""
    if not path:
        report.item(label, "not found")
        report.missing(f"lib{name} (the {label} library) is not installed", _apt(packages))
        return None
    try:
        ctypes.CDLL(path)
    except OSError as exc:
        report.item(label, f"{path}{source}: cannot be loaded")
        fix = _apt(packages)
        if forced:
            fix = f"unset {override} (or point it at lib{name}.so.1); else {fix}"
        report.missing(f"lib{name} {path}{source} cannot be loaded ({_first_line(exc)})", fix)
        return None
    report.item(label, f"{path}{source}")
    return path


def _egl_vendors() -> list[str]:
    dirs = os.environ.get("__EGL_VENDOR_LIBRARY_DIRS")
    folders = dirs.split(":") if dirs else list(DEFAULT_EGL_VENDOR_DIRS)
    found = []
    for folder in folders:
        with_json = sorted(Path(folder).glob("*.json")) if Path(folder).is_dir() else []
        found += [str(p) for p in with_json]
    files = os.environ.get("__EGL_VENDOR_LIBRARY_FILENAMES")
    if files:
        found += [f for f in files.split(":") if f]
    return found


def _check_gl(report: Report) -> None:
    report.section("OpenGL (headless, EGL)")
    egl = _library(report, "libEGL", LIBEGL_OVERRIDE, "EGL", EGL_PACKAGES)
    gl = _library(report, "libGL", LIBGL_OVERRIDE, "GL", LIBGL_PACKAGES)
    vendors = _egl_vendors()
    report.item("EGL vendors", ", ".join(Path(v).name for v in vendors) or "none found")
    if egl is None or gl is None:
        report.item("context", "not tried (library missing)")
        return
    try:
        from envstudio.gpu.context import (
            create_headless_context,
            has_compute,
            is_software_renderer,
        )

        ctx = create_headless_context()
    except Exception as exc:  # ContextError, ImportError of moderngl, driver errors
        report.item("context", f"none ({_first_line(exc)})")
        fix = _apt("libegl-mesa0 libgl1-mesa-dri") + " (or install the GPU's driver)"
        report.missing("no OpenGL 3.3 context through EGL", fix)
        return
    try:
        info = ctx.info
        report.item("renderer", info.get("GL_RENDERER", "?"))
        report.item("vendor", info.get("GL_VENDOR", "?"))
        report.item("version", f"{info.get('GL_VERSION', '?')} (code {ctx.version_code})")
        if is_software_renderer(ctx):
            report.item("note", "software rasteriser: timings use the wall clock, slow")
        compute = has_compute(ctx)
        report.item("compute shaders", "yes (OpenGL 4.3)" if compute else "no (below 4.3)")
        for method, what in NEEDS_COMPUTE:
            mark = "ok" if compute else "unavailable"
            report.lines.append(f"    {method:<10} {mark:<12} needs 4.3 for {what}")
        if not compute:
            report.missing(
                "OpenGL 4.3 (compute shaders) for reference, kautz dynamic, banks builder=gpu",
                _apt("libgl1-mesa-dri") + " (Mesa llvmpipe gives 4.5) or a newer GPU driver",
            )
    finally:
        ctx.release()


# -- window ---------------------------------------------------------------------------------------


def _check_window(report: Report) -> None:
    report.section("Window (moderngl-window + glfw)")
    try:
        import glfw

        native = glfw.get_version_string()
        native = native.decode() if isinstance(native, bytes) else str(native)
        report.item("glfw", f"{metadata.version('glfw')} (libglfw {native})")
    except Exception as exc:
        report.item("glfw", f"unusable ({_first_line(exc)})")
        report.missing(
            "the glfw package or its libglfw",
            _pip("--force-reinstall glfw>=2.7"),
        )
    try:
        import moderngl_window.context.glfw  # noqa: F401

        report.item("moderngl-window", f"{metadata.version('moderngl-window')} (glfw window)")
    except Exception as exc:
        report.item("moderngl-window", f"unusable ({_first_line(exc)})")
        report.missing("moderngl-window's glfw window", _pip("moderngl-window>=3.1"))
    display = os.environ.get("WAYLAND_DISPLAY") or os.environ.get("DISPLAY")
    if display:
        report.item("display", display)
    else:
        xvfb = shutil.which("xvfb-run")
        hint = "xvfb-run -a envstudio view" if xvfb else _apt("xvfb xauth") + ", then xvfb-run"
        report.item("display", f"none: the viewer needs one (headless commands do not): {hint}")


# -- Python ---------------------------------------------------------------------------------------

_REQUIREMENT = re.compile(r"^\s*([A-Za-z0-9][A-Za-z0-9._-]*)\s*([^;]*?)\s*(?:;\s*(.*))?$")


def _lock_pins() -> dict[str, str]:
    """``requirements.lock`` of a source checkout (name → version), empty for a wheel."""
    lock = Path(__file__).resolve().parents[2] / "requirements.lock"
    pins = {}
    if lock.is_file():
        for line in lock.read_text().splitlines():
            name, sep, version = line.strip().partition("==")
            if sep and not name.startswith("#"):
                pins[_normal(name)] = version.strip()
    return pins


def _normal(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _check_python(report: Report) -> None:
    report.section("Python")
    report.item("python", f"{platform.python_version()} ({sys.executable})")
    report.item(DISTRIBUTION, _version())
    try:
        requires = metadata.requires(DISTRIBUTION) or []
    except metadata.PackageNotFoundError:
        requires = []
        report.missing(f"{DISTRIBUTION} is not installed", _pip(".") + "  (from the checkout)")
    pins = _lock_pins()
    differ = []
    for requirement in requires:
        match = _REQUIREMENT.match(requirement)
        if not match:
            continue
        name, spec, marker = match.groups()
        optional = bool(marker and "extra" in marker)
        try:
            have = metadata.version(name)
        except metadata.PackageNotFoundError:
            have = None
        pinned = pins.get(_normal(name))
        label = f"{name} (tests)" if optional else name
        if have is None:
            report.item(label, "not installed" + (" (optional)" if optional else ""))
            if not optional:
                report.missing(
                    f"Python package {name}", _pip(f"{name}=={pinned}" if pinned else name + spec)
                )
            continue
        note = ""
        if pinned and pinned != have:
            note = f" (requirements.lock: {pinned})"
            differ.append(name)
        report.item(label, have + note)
    if differ:
        report.item(
            "note",
            f"{len(differ)} differ from requirements.lock: "
            + _pip("-r requirements.lock").replace("'", ""),
        )


# -- data and folders -----------------------------------------------------------------------------


def _check_folders(report: Report) -> None:
    report.section("Data and folders")
    try:
        from envstudio.resources import asset_root, shader_root

        report.item("shaders", str(shader_root()))
        report.item("assets", str(asset_root()))
    except Exception as exc:
        report.item("shaders/assets", f"not found ({_first_line(exc)})")
        report.missing("the shaders and assets folders", _pip(f"--force-reinstall {DISTRIBUTION}"))
    folders = []
    try:
        from envstudio.measure.ground_truth_cache import cache_dir

        override = " ($ENVSTUDIO_CACHE_DIR)" if os.environ.get("ENVSTUDIO_CACHE_DIR") else ""
        folders.append(("cache", cache_dir(), override))
    except Exception as exc:
        report.item("cache", f"unknown ({_first_line(exc)})")
    try:
        from envstudio.ui.settings import config_location

        override = " ($ENVSTUDIO_CONFIG_DIR)" if os.environ.get("ENVSTUDIO_CONFIG_DIR") else ""
        folders.append(("config", config_location(), override))
    except Exception as exc:
        report.item("config", f"unknown ({_first_line(exc)})")
    for name, folder, override in folders:
        if folder.is_dir():
            size, files = _folder_size(folder)
            report.item(name, f"{folder}{override}: {_human(size)} in {files} files")
        else:
            report.item(name, f"{folder}{override}: not created yet")


def run_doctor(out=None) -> int:
    """Print the report to ``out`` (stdout); 0 when nothing is missing, else 1."""
    out = out or sys.stdout
    report = Report()
    report.lines.append(f"envstudio {_version()} on {platform.platform()}")
    for check in (_check_gl, _check_window, _check_python, _check_folders):
        try:
            check(report)
        except Exception as exc:  # a probe's own bug must not hide the others
            report.item("error", f"{check.__name__[7:]} check failed: {_first_line(exc)}")
            report.missing(f"{check.__name__[7:]} check failed", "report it with this output")
    report.section("Missing")
    if not report.problems:
        report.lines.append("  nothing: everything envstudio uses is here")
    for what, fix in report.problems:
        report.lines.append(f"  {what}")
        report.lines.append(f"    fix: {fix}")
    print("\n".join(report.lines), file=out)
    return 1 if report.problems else 0
