"""What each ``envstudio`` subcommand does (argument parsing lives in :mod:`envstudio.cli`)."""

from __future__ import annotations

import argparse
import json
import sys

from tqdm import tqdm

from envstudio.errors import ParameterError
from envstudio.io.atomic import check_output_path, write_text_atomic
from envstudio.io.images import write_image
from envstudio.methods.base import Method, available_methods, method_class
from envstudio.methods.parameters import parse_assignments
from envstudio.render.display import DISPLAY_PARAMETERS
from envstudio.render.session import RenderSession
from envstudio.scene.graph import Scene
from envstudio.scene_setup import build_scene, parse_camera, parse_size

_DISPLAY_NAMES = tuple(p.name for p in DISPLAY_PARAMETERS)


def apply_params(session: RenderSession, method: Method, assignments: list[str]) -> None:
    """Apply ``name=value`` strings to the method's or the display's parameters."""
    for name, value in parse_assignments(assignments).items():
        if name in method.values:
            method.values[name] = value
        elif name in _DISPLAY_NAMES:
            session.renderer.display[name] = value
        else:
            own = ", ".join(p.name for p in method.values) or "none"
            raise ParameterError(
                f"unknown parameter {name!r} for method {method.name} "
                f"(method: {own}; display: {', '.join(_DISPLAY_NAMES)})"
            )


def _scene(args: argparse.Namespace) -> Scene:
    return build_scene(args.scene, args.env, args.mesh)


def run_render(args: argparse.Namespace) -> int:
    """``envstudio render``: one frame through EGL to PNG (as displayed) or EXR (linear)."""
    size = parse_size(args.size)
    output = check_output_path(args.output)
    if output.suffix.lower() not in (".png", ".exr"):
        raise ParameterError(f"-o {output}: expected a .png or .exr file name")
    method_class(args.method)
    camera = parse_camera(args.camera) if args.camera else None
    scene = _scene(args)
    session = RenderSession(scene)
    try:
        method = session.method(args.method)
        apply_params(session, method, args.param)
        if camera:
            session.camera.azimuth, session.camera.elevation, session.camera.distance = camera
        stats = render_until_finished(session, method, size)
        pixels = session.read_hdr() if output.suffix.lower() == ".exr" else session.read_ldr()
        write_image(output, pixels)
    finally:
        session.release()
    print(f"{output}: {args.method} {size[0]}x{size[1]} in {stats.total_ms:.1f} ms ({stats.clock})")
    return 0


def render_until_finished(session: RenderSession, method: Method, size: tuple[int, int]):
    """Render frames until the method is finished (one for one-shot methods), with progress."""
    stats = session.render_offscreen(method, size)
    if method.finished():
        return stats
    with tqdm(
        desc=method.name,
        unit="frame",
        file=sys.stderr,
        disable=not sys.stderr.isatty(),
        bar_format="{desc}: {n} frames {elapsed} {postfix}",
    ) as bar:
        while not method.finished():
            stats = session.render_offscreen(method, size)
            bar.update(1)
            bar.set_postfix_str(method.status_line())
    if method.status_line():
        print(f"{method.name}: {method.status_line()}", file=sys.stderr)
    return stats


def run_envmap(args: argparse.Namespace) -> int:
    """``envstudio envmap``: the environment in another representation, as linear EXR."""
    from envstudio.envmap.conversions import upload_latlong
    from envstudio.envmap.export import export_environment
    from envstudio.gpu.context import create_headless_context
    from envstudio.gpu.programs import ProgramLibrary
    from envstudio.io.images import read_environment

    output = check_output_path(args.output)
    if output.suffix.lower() != ".exr":
        raise ParameterError(f"-o {output}: expected an .exr file name")
    if not 1 <= args.size <= 8192 or not 0 <= args.border < args.size // 2:
        raise ParameterError(
            f"--size {args.size} --border {args.border}: expected 1..8192 and 0 <= border < size/2"
        )
    radiance = read_environment(args.env)
    ctx = create_headless_context()
    programs = ProgramLibrary(ctx)
    try:
        latlong = upload_latlong(ctx, radiance)
        path = export_environment(ctx, programs, latlong, args.to, args.size, args.border, output)
    finally:
        programs.release()
        ctx.release()
    print(f"{path}: {args.to} from {args.env}")
    return 0


def run_methods(args: argparse.Namespace) -> int:
    """``envstudio methods``: every method with its declared parameters."""
    described = [cls.describe() for cls in available_methods().values()]
    if args.json:
        print(
            json.dumps(
                {"methods": described, "display": [p.describe() for p in DISPLAY_PARAMETERS]},
                indent=2,
            )
        )
        return 0
    for entry in described:
        print(f"{entry['name']}: {entry['title']} — {entry['summary']}")
        for p in entry["parameters"]:
            rng = f" [{p['minimum']:g}, {p['maximum']:g}]" if "minimum" in p else ""
            choices = f" {{{', '.join(p['choices'])}}}" if "choices" in p else ""
            unit = f" {p['unit']}" if p.get("unit") else ""
            print(
                f"  {p['name']} ({p['kind']}{rng}{choices}, default {p['default']}{unit}): "
                f"{p.get('help', '')}"
            )
    return 0


def run_bench(args: argparse.Namespace) -> int:
    """``envstudio bench``: per-method frame and pass times."""
    from envstudio.render.bench import format_report
    from envstudio.render.bench import run_bench as bench

    size = parse_size(args.size)
    names = args.methods.split(",") if args.methods else list(available_methods())
    for name in names:
        method_class(name)
    if args.frames < 1 or args.warmup < 0:
        raise ParameterError("--frames must be >= 1 and --warmup >= 0")
    json_out = check_output_path(args.json_out) if args.json_out else None
    scene = _scene(args)
    if args.triangles:
        from envstudio.scene_setup import subdivide_reflectors

        subdivide_reflectors(scene, args.triangles)
    session = RenderSession(scene)
    try:
        for name in names:
            apply_params(
                session,
                session.method(name),
                [
                    a
                    for a in args.param
                    if a.partition("=")[0] in session.method(name).values
                    or a.partition("=")[0] in _DISPLAY_NAMES
                ],
            )
        report = bench(session, names, size, args.frames, args.warmup, progress=sys.stderr.isatty())
    finally:
        session.release()
    print(format_report(report))
    if json_out:
        write_text_atomic(json_out, json.dumps(report, indent=2))
    return 0


def run_fit_glossiness(args: argparse.Namespace) -> int:
    """``envstudio fit-glossiness``: refit the LOD bias ↔ Phong exponent match (seed 000 §6)."""
    from envstudio.io.images import read_environment
    from envstudio.io.scene_file import shipped_environments
    from envstudio.prefilter import glossiness

    out = check_output_path(args.out) if args.out else glossiness.DATA_FILE
    sizes = args.sizes or glossiness.DEFAULT_SIZES
    if any(n < 4 or n & (n - 1) for n in sizes):
        raise ParameterError(f"--sizes {' '.join(map(str, sizes))}: expected powers of two >= 4")
    directions = glossiness.DEFAULT_DIRECTIONS if args.directions is None else args.directions
    if directions < 16:
        raise ParameterError(f"--directions {directions}: expected at least 16")
    shipped = shipped_environments()
    names = args.environments or glossiness.FIT_ENVIRONMENTS
    unknown = [name for name in names if name not in shipped]
    if unknown:
        raise ParameterError(
            f"--environments {' '.join(unknown)}: not shipped (shipped: {', '.join(shipped)})"
        )
    environments = {name: read_environment(shipped[name]) for name in names}
    with tqdm(
        desc="fit-glossiness", unit="step", file=sys.stderr, disable=not sys.stderr.isatty()
    ) as bar:

        def progress(done: int, total: int) -> None:
            bar.total = total
            bar.update(done - bar.n)

        fit = glossiness.fit_glossiness(
            environments, sizes, directions=directions, progress=progress
        )
    write_text_atomic(out, json.dumps(fit, indent=1) + "\n")
    model = fit["model"]
    a, c, d = (model["coefficients"][k] for k in "acd")
    print(
        f"{out}: b = W({a:.4f} + {c:.4f} log2(n) {d:+.4f} log2(N)), residual rms "
        f"{model['residual_rms']:.3f} levels over {model['points_used']} points"
    )
    return 0


def run_compare(args: argparse.Namespace) -> int:
    """``envstudio compare``: methods against the converged reference, files and a table."""
    from envstudio.core.metrics import MIN_SIZE
    from envstudio.render.compare import method_classes, plan_parameters, run_comparison
    from envstudio.render.report import format_table, write_report

    size = parse_size(args.size)
    if min(size) < MIN_SIZE:
        raise ParameterError(f"--size {args.size}: compare needs at least {MIN_SIZE}x{MIN_SIZE}")
    names = [name.strip() for name in args.methods.split(",") if name.strip()]
    if not names:
        raise ParameterError(f"--methods {args.methods!r}: expected comma-separated method names")
    plan = plan_parameters(method_classes(names), args.param)
    if args.frames < 1 or args.warmup < 0:
        raise ParameterError("--frames must be >= 1 and --warmup >= 0")
    out = check_output_path(args.out)
    camera = parse_camera(args.camera) if args.camera else None
    session = RenderSession(_scene(args))
    try:
        if camera:
            session.camera.azimuth, session.camera.elevation, session.camera.distance = camera
        comparison = run_comparison(
            session, names, size, plan, args.frames, args.warmup, progress=sys.stderr.isatty()
        )
    finally:
        session.release()
    write_report(comparison, out)
    print(format_table(comparison))
    if not comparison.reliable:
        print(
            f"envstudio: warning: metrics unreliable: {comparison.reference.unreliable_reason}",
            file=sys.stderr,
        )
    return 0


def run_view(args: argparse.Namespace) -> int:
    """``envstudio view``: the desktop viewer."""
    from envstudio.ui.app import run_viewer

    return run_viewer(args)
