"""What each ``envstudio`` subcommand does (argument parsing lives in :mod:`envstudio.cli`)."""

from __future__ import annotations

import argparse
import json
import math
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


def parse_time_limit(text: str | None) -> float | None:
    """``--time-limit SECONDS`` as a float (None when not given).

    Raises
    ------
    ParameterError
        Unless a finite number > 0 and at most the reference's ``time_limit`` maximum.
    """
    if text is None:
        return None
    from envstudio.methods.reference import MAX_TIME_LIMIT_S

    try:
        seconds = float(text)
    except ValueError:
        seconds = math.nan
    if not 0 < seconds <= MAX_TIME_LIMIT_S:
        raise ParameterError(
            f"--time-limit {text}: expected a positive number of seconds "
            f"(at most {MAX_TIME_LIMIT_S:g})"
        )
    return seconds


def run_render(args: argparse.Namespace) -> int:
    """``envstudio render``: one frame through EGL to PNG (as displayed) or EXR (linear)."""
    size = parse_size(args.size)
    output = check_output_path(args.output)
    if output.suffix.lower() not in (".png", ".exr"):
        raise ParameterError(f"-o {output}: expected a .png or .exr file name")
    declared = {p.name for p in method_class(args.method).parameters}
    time_limit = parse_time_limit(args.time_limit)
    if time_limit is not None and "time_limit" not in declared:
        raise ParameterError(
            f"--time-limit: method {args.method} draws its image in one frame "
            "(only progressive methods, such as reference, take a time limit)"
        )
    camera = parse_camera(args.camera) if args.camera else None
    scene = _scene(args)
    session = RenderSession(scene)
    try:
        method = session.method(args.method)
        apply_params(session, method, args.param)
        if time_limit is not None:
            method.values["time_limit"] = time_limit
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


def default_bench_methods() -> list[str]:
    """What ``bench`` times without ``--methods``: every method that draws its image in one frame.

    A progressive method's frame is one batch of an accumulation (a reference
    batch at 1280x720 takes seconds on a software renderer); name it with
    ``--methods`` to time its batches, or use ``bench --converge``.
    """
    return [name for name, cls in available_methods().items() if not cls.progressive]


def run_bench(args: argparse.Namespace) -> int:
    """``envstudio bench``: per-method frame and pass times."""
    from envstudio.render.bench import format_report
    from envstudio.render.bench import run_bench as bench

    if args.prefilter:
        from envstudio.render.prefilter_command import run_prefilter_bench

        return run_prefilter_bench(args)
    size = parse_size(args.size or "1280x720")
    if args.hwconv_table or args.hwconv_accuracy:
        return _run_hwconv_table(args, size)
    if args.converge:
        return _run_convergence(args, size)
    if args.resume:
        raise ParameterError("--resume: only with --converge (it resumes a reference accumulation)")
    names = args.methods.split(",") if args.methods else default_bench_methods()
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


def _run_hwconv_table(args: argparse.Namespace, size: tuple[int, int]) -> int:
    """``envstudio bench --methods hwconv --hwconv-table``: seed 004 §5.2's table;
    ``--hwconv-accuracy``: its error against the brute-force Phong prefilter."""
    from envstudio.render.hwconv_accuracy import (
        format_accuracy,
        format_error_images,
        run_accuracy,
        write_error_images,
    )
    from envstudio.render.hwconv_bench import format_table, run_table

    flag = "--hwconv-accuracy" if args.hwconv_accuracy else "--hwconv-table"
    if args.hwconv_table and args.hwconv_accuracy:
        raise ParameterError("--hwconv-table --hwconv-accuracy: expected one of them")
    if args.methods not in (None, "hwconv"):
        raise ParameterError(f"{flag} --methods {args.methods}: only 'hwconv' has it")
    if args.frames < 1 or args.warmup < 0:
        raise ParameterError("--frames must be >= 1 and --warmup >= 0")
    if args.directions < 1:
        raise ParameterError(f"--directions {args.directions}: expected an integer >= 1")
    try:
        exponents = [float(e) for e in args.exponents.split(",")]
    except ValueError:
        raise ParameterError(f"--exponents {args.exponents}: expected numbers > 0") from None
    json_out = check_output_path(args.json_out) if args.json_out else None
    session = RenderSession(_scene(args))
    try:
        session.method("hwconv").values["map_size"] = 512  # the paper's; --param overrides
        apply_params(session, session.method("hwconv"), args.param)
        if args.hwconv_accuracy:
            errors: dict = {}
            report = run_accuracy(
                session, exponents, args.directions, progress=sys.stderr.isatty(), errors=errors
            )
        else:
            report = run_table(
                session, exponents, size, args.frames, args.warmup, progress=sys.stderr.isatty()
            )
    finally:
        session.release()
    print(format_accuracy(report) if args.hwconv_accuracy else format_table(report))
    if json_out and args.hwconv_accuracy:  # the error images beside OUT, listed in it
        images = write_error_images(report, errors, json_out)
        report["error_images"] = {"scale": 1.0, "files": [p.name for p in images]}
        print(format_error_images(images, 1.0))
    if json_out:
        write_text_atomic(json_out, json.dumps(report, indent=2))
    return 0


def _run_convergence(args: argparse.Namespace, size: tuple[int, int]) -> int:
    """``envstudio bench --converge``: the reference's time to its tolerance."""
    from envstudio.render.convergence import format_convergence, run_convergence

    if args.methods not in (None, "reference"):
        raise ParameterError(f"--converge --methods {args.methods}: only 'reference' converges")
    if not args.time_limit > 0:
        raise ParameterError(f"--time-limit {args.time_limit}: expected a positive number")
    json_out = check_output_path(args.json_out) if args.json_out else None
    session = RenderSession(_scene(args))
    try:
        method = session.method("reference")
        apply_params(session, method, args.param)
        report = run_convergence(
            session,
            method,
            size,
            args.time_limit,
            progress=sys.stderr.isatty(),
            resume=args.resume,
        )
    finally:
        session.release()
    print(format_convergence(report))
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


def run_prefilter(args: argparse.Namespace) -> int:
    """``envstudio prefilter``: a prefiltered environment map computed on the CPU (seed 004)."""
    from envstudio.render.prefilter_command import run_prefilter as prefilter

    return prefilter(args)


def run_bake(args: argparse.Namespace) -> int:
    """``envstudio bake rsibr`` (seed 002, .rsibr) or ``bake pem`` (seed 003, .pem)."""
    if args.kind == "pem":
        from envstudio.render.pem_command import run_bake_pem

        return run_bake_pem(args)
    from envstudio.render.rsibr_command import run_bake_rsibr

    for name, value in (("size", 64), ("views", 12), ("samples", 256)):
        if getattr(args, name) is None:
            setattr(args, name, value)
    if args.env is None:
        raise ParameterError("bake rsibr: --env is required (a lat-long .exr or .hdr)")
    return run_bake_rsibr(args)


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
    time_limit = parse_time_limit(args.time_limit)
    out = check_output_path(args.out)
    camera = parse_camera(args.camera) if args.camera else None
    session = RenderSession(_scene(args))
    try:
        if camera:
            session.camera.azimuth, session.camera.elevation, session.camera.distance = camera
        comparison = run_comparison(
            session,
            names,
            size,
            plan,
            args.frames,
            args.warmup,
            progress=sys.stderr.isatty(),
            cache=args.cache,
            strict=args.strict,
            time_limit_s=time_limit,
            extras_dir=out,
        )
    finally:
        session.release()
    write_report(comparison, out)
    print(format_table(comparison))
    note = _time_limit_note(comparison.reference)
    if note:
        print(f"envstudio: note: {note}", file=sys.stderr)
    if not comparison.reliable:
        print(
            f"envstudio: warning: metrics unreliable: {comparison.reference.unreliable_reason}",
            file=sys.stderr,
        )
    return 0


def _time_limit_note(reference) -> str | None:
    """One line when the time limit ended a strict (tolerance) run before it converged."""
    from envstudio.render.stopping import TOLERANCE_RULE

    if reference.stopping_rule != TOLERANCE_RULE or reference.stopped_by != "time_limit":
        return None
    change = reference.status.rms_change
    reached = "no half-change measured" if change is None else f"half-change {100 * change:.3g} %"
    return (
        f"the time limit ({float(reference.parameters['time_limit']):g} s) ended before the "
        f"tolerance ({100 * float(reference.parameters['tolerance']):.3g} %): {reached} at "
        f"{reference.status.samples} spp, reported as NOT converged"
    )


def run_sh(args: argparse.Namespace) -> int:
    """``envstudio sh``: SH coefficients and extracted lights of an environment (seed 000 §4.1)."""
    import time

    from envstudio.core import cubemap, latlong
    from envstudio.core.resample import latlong_to_cube
    from envstudio.core.sh_bands import BAND_SETS, band_indices
    from envstudio.core.sh_lights import DiffuseProjector
    from envstudio.io.images import read_environment
    from envstudio.prefilter.brute_force import downsample_latlong

    if not 0 <= args.lights <= 32 or not args.threshold > 0:
        raise ParameterError(
            f"--lights {args.lights} --threshold {args.threshold}: expected 0..32 and > 0"
        )
    if args.cube is not None and not 8 <= args.cube <= 1024:
        raise ParameterError(f"--cube {args.cube}: expected a face size in 8..1024")
    radiance = read_environment(args.env)
    if args.height is not None:
        if args.height < 1 or radiance.shape[0] % args.height:
            raise ParameterError(
                f"--height {args.height}: expected a divisor of the map's {radiance.shape[0]} rows"
            )
        radiance = downsample_latlong(radiance, args.height)
    if args.cube:
        samples = latlong_to_cube(radiance, args.cube)
        directions = cubemap.texel_directions(args.cube)
        solid_angles = cubemap.texel_solid_angles(args.cube)
        source = f"6x{args.cube}x{args.cube} cube"
    else:
        samples = radiance
        directions = latlong.texel_directions(*radiance.shape[:2])
        solid_angles = latlong.texel_solid_angles(*radiance.shape[:2])
        source = f"{radiance.shape[1]}x{radiance.shape[0]} lat-long"
    projector = DiffuseProjector(
        directions,
        solid_angles,
        coefficients=args.coefficients,
        lights=args.lights,
        threshold=args.threshold,
    )
    times = []
    for _ in range(5):
        start = time.perf_counter()
        lighting = projector.project(samples)
        times.append((time.perf_counter() - start) * 1e3)
    degree, order = band_indices(BAND_SETS[args.coefficients])
    report = {
        "environment": str(args.env),
        "source": source,
        "order": "seed 000 eq. 9 (bands 0, 1, 2, then the even bands), m = -l..l",
        "l": degree.tolist(),
        "m": order.tolist(),
        "coefficients": lighting.coefficients.tolist(),
        "lights": [
            {"direction": row[:3].tolist(), "sin2_alpha": float(row[3]), "rgb": row[4:].tolist()}
            for row in lighting.lights
        ],
        "projection_ms": min(times),
    }
    if args.check:
        report["check"] = _irradiance_check(samples, directions, solid_angles, lighting)
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    residual = f" of the residual after {len(lighting.lights)} lights" if args.lights else ""
    print(f"{args.env}: {source} projected in {min(times):.2f} ms (best of 5); L_i{residual}")
    print(f"{'i':>3} {'Y_i':<7} {'l':>2} {'m':>3} {'R':>12} {'G':>12} {'B':>12}")
    for i, rgb in enumerate(lighting.coefficients):
        name = _SH9_NAMES[i] if i < len(_SH9_NAMES) else ""
        values = " ".join(f"{v:>12.6g}" for v in rgb)
        print(f"{i:>3} {name:<7} {degree[i]:>2} {order[i]:>3} {values}")
    for k, light in enumerate(report["lights"]):
        d = ", ".join(f"{v:+.4f}" for v in light["direction"])
        rgb = " ".join(f"{v:.6g}" for v in light["rgb"])
        print(f"light {k:>2}: direction ({d}) sin²α {light['sin2_alpha']:.3g} moment {rgb}")
    if args.check:
        check = report["check"]
        print(
            f"irradiance vs brute force over the same {source} ({check['normals']} random "
            f"normals, luminance): mean {check['mean_relative_error'] * 100:.2f} %, "
            f"max {check['max_relative_error'] * 100:.2f} %"
        )
    return 0


# The basis functions of seed 000 eq. 9, by index.
_SH9_NAMES = ("1", "y", "z", "x", "xy", "yz", "3z²-1", "xz", "x²-y²")


def _irradiance_check(radiance, directions, solid_angles, lighting, normals: int = 2000) -> dict:
    """Relative error (luminance) of ``lighting``'s irradiance against the brute-force sum
    Σ_k L_k max(n·d_k, 0) Δω_k over the samples it was projected from."""
    import numpy as np

    from envstudio.core.env_sampling import luminance

    n = np.random.default_rng(0).normal(size=(normals, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    weighted = luminance(radiance).reshape(-1) * np.asarray(solid_angles).reshape(-1)
    truth = np.concatenate(
        [np.maximum(n[i : i + 16] @ d.T, 0.0) @ weighted for i in range(0, normals, 16)]
    )
    error = np.abs(luminance(lighting.irradiance(n)) - truth) / truth
    return {
        "normals": normals,
        "mean_relative_error": float(error.mean()),
        "max_relative_error": float(error.max()),
    }


def run_figure(args: argparse.Namespace) -> int:
    """``envstudio figure``: seed 000 Figure 6 (kautz-grid) or Figure 4 (kautz-seams),
    seed 004 Figure 3 (hwconv-distortion)."""
    from envstudio.render import figures

    size = parse_size(args.size)
    output = check_output_path(args.output)
    if output.suffix.lower() != ".png":
        raise ParameterError(f"-o {output}: expected a .png file name")
    if args.name == "hwconv-distortion":
        numbers = figures.write_distortion_figure(output)
        radii = figures.FIGURE3_RADII
        print(
            f"{output}: distortion e(r, d) against d for r = {', '.join(map(str, radii))} "
            f"(left), border distance over ρ at r = {max(radii)} (right); "
            f"largest e {100 * numbers['max_error']:.1f} %"
        )
        for exponent, (r_l, e) in numbers["table"].items():
            print(f"N = {exponent:>3}: r_l = {r_l:.3f} of the disc's radius, at the rim {e:.1%}")
        return 0
    camera = parse_camera(args.camera) if args.camera else None
    session = RenderSession(_scene(args))
    try:
        if camera:
            session.camera.azimuth, session.camera.elevation, session.camera.distance = camera
        if args.name == "rsibr-warp":
            from envstudio.methods.rsibr import figure as rsibr_figure

            method = session.method("rsibr")
            apply_params(session, method, args.param)
            session.render_offscreen(method, size)
            figure = rsibr_figure.figure4(method, method.last_frame_d)
            n = figure.generated.shape[0]
            display = session.renderer.display
            image = rsibr_figure.figure_image(
                figure,
                float(display["exposure"]),
                str(display["tonemap"]),
                scale=max(1, size[1] // n),
            )
            write_image(output, image)
            weights = ", ".join(
                f"view {i} w = {w:.4f}" for i, w in zip(figure.indices, figure.weights, strict=True)
            )
            print(
                f"{output}: top: source maps ({weights}); bottom: each warped into the "
                f"camera's frame (times its singularity fade), then the generated map ({n}²)"
            )
            return 0
        if args.name == "pem-maps":
            from envstudio.methods.pem import offmanifold
            from envstudio.methods.pem.blending import view_blend

            method = session.method("pem")
            apply_params(session, method, args.param)
            method.prepare(session.gpu_scene)
            if method.bake is None:
                raise ParameterError(f"pem: {method.status_line()}")
            blend = view_blend(method.bake.view_space, session.camera.position, blend=False)
            display = session.renderer.display
            offmanifold.maps_figure(
                method.bake,
                blend.views[0],
                0,
                output,
                float(display["exposure"]),
                str(display["tonemap"]),
            )
            print(
                f"{output}: view {blend.views[0]} (nearest the camera), part "
                f"{method.bake.parts[0]!r}: rows distant, local α·L, local α, sphere; "
                "columns MIP levels"
            )
            return 0
        if args.name == "pem-offmanifold":
            from envstudio.methods.pem import offmanifold

            method = session.method("pem")
            apply_params(session, method, args.param)
            method.prepare(session.gpu_scene)
            if method.bake is None:
                raise ParameterError(f"pem: {method.status_line()}")
            results = offmanifold.measure(session, method, size=size[1])
            offmanifold.figure_image(results, output)
            print(f"{output}: rows: views off the baked arc; columns: ray trace, layered PEM, ")
            print("sphere at infinity, static EM (displayed PSNR dB / FLIP, * best)")
            for r in results:
                cells = "  ".join(
                    f"{m} {v['psnr']:.2f} dB / {v['flip']:.4f}" for m, v in r.metrics.items()
                )
                print(
                    f"{r.view.label:>14} (az {r.view.azimuth:.2f}°, el {r.view.elevation:.2f}°): "
                    f"{cells}"
                )
            return 0
        if args.name == "banks-slices":
            from envstudio.render import banks_figure

            method = session.method("banks")
            method.values.update(banks_figure.FIGURE6_VALUES)
            apply_params(session, method, args.param)
            image = banks_figure.render_slices(session, method, size)
            angles = ", ".join(f"{a:g}°" for a in banks_figure.SLICE_ANGLES)
            layout = f"s = {method.values['sharpness']:g}: reflector, slices at ∠(v,t) = {angles}"
            write_image(output, image)
            print(f"{output}: {layout}")
            return 0
        method = session.method("kautz")
        if args.name == "kautz-grid":
            method.values.update(figures.FIGURE6_VALUES)
            apply_params(session, method, args.param)
            image = figures.render_figure6(session, size)
            layout = (
                f"rows b = {', '.join(map(str, figures.FIGURE6_LOD_BIAS))} (top to bottom), "
                f"columns f_λ = {', '.join(map(str, figures.FIGURE6_FRESNEL))} (left to right)"
            )
        else:
            method.values.update(figures.SEAM_VALUES)
            apply_params(session, method, args.param)
            image = figures.render_seam_pair(session, size)
            layout = f"b = {figures.SEAM_LOD_BIAS}: box mip chain (left), cross-face (right)"
            levels = figures.seam_levels(session)
        write_image(output, image)
    finally:
        session.release()
    print(f"{output}: {layout}")
    if args.name == "kautz-seams":
        print("mean step between neighbouring texels, across face edges / inside faces:")
        print(
            f"{'level':>5} {'face':>5} {'box across':>11} {'inside':>8} {'ratio':>6}   "
            f"{'cross-face across':>17} {'inside':>8} {'ratio':>6}"
        )
        for s in levels:
            print(
                f"{s.level:>5} {s.size:>5} {s.box_across:>11.4g} {s.box_inside:>8.4g} "
                f"{s.box_across / s.box_inside:>6.2f}   {s.cross_across:>17.4g} "
                f"{s.cross_inside:>8.4g} {s.cross_across / s.cross_inside:>6.2f}"
            )
    return 0


def run_view(args: argparse.Namespace) -> int:
    """``envstudio view``: the desktop viewer."""
    from envstudio.ui.app import run_viewer

    return run_viewer(args)
