"""The ``envstudio`` command: view (default), render, methods, bench, sh, figure, doctor, …

Usage errors print one line and exit with status 2; nothing prints a traceback
for bad input.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
from collections.abc import Sequence

from envstudio.errors import ContextError, InputFileError, ParameterError, UserError


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (exit status 2)."""

    def error(self, message: str):
        raise ParameterError(f"{self.prog}: {message}")


def _add_scene_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--scene", help="shipped scene name (studio, room) or a TOML scene file")
    parser.add_argument("--env", help="lat-long environment (.exr or .hdr), replaces the scene's")
    parser.add_argument(
        "--mesh", help="mesh file (OBJ, PLY, STL, OFF, GLB), replaces the reflector"
    )


def _add_param_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="method or display parameter (repeatable), e.g. lod_bias=2.3",
    )


def _add_time_limit_option(parser: argparse.ArgumentParser, what: str) -> None:
    parser.add_argument(
        "--time-limit",
        metavar="SECONDS",
        help=f"{what} this many seconds and report the noise reached (a positive number)",
    )


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    from envstudio import __version__

    parser = _Parser(prog="envstudio", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", parser_class=_Parser)
    sub.add_parser(
        "doctor",
        help="what this machine has (GL, EGL, window, packages, folders) and what is missing",
    )

    view = sub.add_parser("view", help="open the viewer window (the default)")
    view.add_argument(
        "file",
        nargs="?",
        help="an environment (.exr, .hdr), a mesh or a scene (.toml) to open: what a file "
        "manager passes (the desktop entry runs `envstudio view FILE`)",
    )
    _add_scene_options(view)
    view.add_argument("--method", help="method shown first")
    view.add_argument(
        "--frames", type=int, default=0, help="quit after this many frames (0: run until closed)"
    )
    view.add_argument("--screenshot", help="save a screenshot (with the UI) before quitting")
    view.add_argument(
        "--compare", metavar="METHOD", help="start in split screen against this method"
    )
    view.add_argument(
        "--cycle-methods",
        action="store_true",
        help="switch to the next method every few frames (smoke tests)",
    )

    render = sub.add_parser("render", help="render one frame headless (EGL)")
    _add_scene_options(render)
    render.add_argument("--method", default="mirror", help="method name (envstudio methods)")
    _add_param_option(render)
    render.add_argument("--camera", help="AZIMUTH,ELEVATION,DISTANCE in degrees and scene units")
    render.add_argument("--size", default="512x512", help="WIDTHxHEIGHT (default 512x512)")
    _add_time_limit_option(render, "progressive methods (reference): stop accumulating after")
    render.add_argument("-o", "--output", required=True, help="OUT.png (as displayed) or OUT.exr")

    envmap = sub.add_parser("envmap", help="convert an environment (GPU) and save it as EXR")
    envmap.add_argument("--env", required=True, help="lat-long environment (.exr or .hdr)")
    envmap.add_argument(
        "--to",
        required=True,
        choices=("latlong", "cube", "paraboloid", "spheremap"),
        help="representation (cube: horizontal cross; paraboloid: front | back)",
    )
    envmap.add_argument("--size", type=int, default=256, help="face / output edge in texels")
    envmap.add_argument("--border", type=int, default=0, help="paraboloid border in texels")
    envmap.add_argument("-o", "--output", required=True, help="OUT.exr")

    methods = sub.add_parser("methods", help="list the methods and their parameters")
    methods.add_argument("--json", action="store_true", help="machine-readable output")

    bench = sub.add_parser("bench", help="time every method per frame and per pass")
    _add_scene_options(bench)
    bench.add_argument(
        "--methods",
        help="comma-separated method names (default: all but the progressive reference, "
        "whose frame is one batch; see --converge)",
    )
    bench.add_argument(
        "--size",
        help="WIDTHxHEIGHT (default 1280x720); with --prefilter the paraboloid map, "
        "FACExWIDTH (default 128x256, two 128-texel faces)",
    )
    bench.add_argument("--frames", type=int, default=60, help="measured frames per method")
    bench.add_argument("--warmup", type=int, default=5, help="unmeasured frames per method")
    bench.add_argument(
        "--triangles",
        type=int,
        default=0,
        help="subdivide the reflector until it has at least this many triangles",
    )
    bench.add_argument(
        "--converge",
        action="store_true",
        help="time the reference to its tolerance (successive-half change) instead",
    )
    bench.add_argument(
        "--time-limit",
        type=float,
        default=3600.0,
        help="with --converge: stop after this many seconds and project the rest",
    )
    bench.add_argument(
        "--resume",
        action="store_true",
        help="with --converge: continue the saved accumulation of an earlier run of the same "
        "inputs and save this one every minute (seconds then count all the runs)",
    )
    bench.add_argument(
        "--prefilter",
        action="store_true",
        help="seed 004 §5.1's table instead: brute-force vs hierarchical Phong prefilter "
        "(CPU), and with --json the time-against-size plot as PNG beside it",
    )
    bench.add_argument(
        "--chain",
        action="store_true",
        help="with --prefilter: the Phong cube mip chains instead, spectral (CPU) and GPU "
        "(8 levels at 128² and 256², time against cmft's and every level's error to the "
        "brute force)",
    )
    bench.add_argument(
        "--exponents",
        default="10,50,100,250,500",
        help="with --prefilter, --hwconv-table or --hwconv-accuracy: comma-separated Phong "
        "exponents "
        "(default 10,50,100,250,500)",
    )
    bench.add_argument(
        "--hwconv-table",
        action="store_true",
        help="seed 004 §5.2's table for --methods hwconv: filter sizes and shrink factors "
        "beside the paper's, refilter + render per frame (2-pass, 1-pass) over the static map",
    )
    bench.add_argument(
        "--hwconv-accuracy",
        action="store_true",
        help="for --methods hwconv: RMS and max relative error of 2-pass, 1-pass and exact "
        "against the brute-force Phong prefilter at --exponents (map_size 512 unless --param); "
        "with --json, the error images per exponent as PNGs beside it (OUT.error_N<N>.png)",
    )
    bench.add_argument(
        "--directions",
        type=int,
        default=8192,
        help="with --hwconv-accuracy: lookup directions over the sphere (default 8192)",
    )
    _add_param_option(bench)
    bench.add_argument("--json", dest="json_out", help="write the report as JSON here")

    _add_prefilter_parser(sub)

    compare = sub.add_parser(
        "compare", help="measure methods against the converged reference (PSNR, SSIM, FLIP)"
    )
    _add_scene_options(compare)
    compare.add_argument("--methods", required=True, help="comma-separated method names")
    compare.add_argument("--camera", help="AZIMUTH,ELEVATION,DISTANCE in degrees and scene units")
    compare.add_argument("--size", default="256x256", help="WIDTHxHEIGHT (default 256x256)")
    compare.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="parameter for every method that declares it, the reference's included "
        "(repeatable), e.g. phong_exponent=50 or max_samples=1024",
    )
    compare.add_argument(
        "--strict",
        action="store_true",
        help="accumulate the reference until its successive-half change is below tolerance "
        "(default: until its noise is under a tenth of every method's error; an explicit "
        "--param tolerance=... is strict too)",
    )
    _add_time_limit_option(compare, "stop the reference after")
    compare.add_argument("--frames", type=int, default=20, help="timed frames per method")
    compare.add_argument("--warmup", type=int, default=3, help="untimed frames per method")
    compare.add_argument("--out", required=True, help="folder for the images, table and index.html")
    compare.add_argument(
        "--no-cache",
        dest="cache",
        action="store_false",
        help="neither resume nor save the reference's accumulation "
        "(default: kept in $ENVSTUDIO_CACHE_DIR or ~/.cache/envstudio)",
    )

    fit = sub.add_parser(
        "fit-glossiness",
        help="refit the LOD bias <-> Phong exponent match (minutes; CPU only)",
    )
    fit.add_argument("--out", help="JSON file to write (default: the package's stored fit)")
    fit.add_argument(
        "--sizes", type=int, nargs="+", help="cube face sizes, powers of two (default 64..512)"
    )
    fit.add_argument("--environments", nargs="+", metavar="NAME", help="shipped maps to fit")
    fit.add_argument("--directions", type=int, help="reflection directions per environment")

    sh = sub.add_parser("sh", help="SH coefficients of an environment (seed 000 eq. 9-11)")
    sh.add_argument("--env", required=True, help="lat-long environment (.exr or .hdr)")
    sh.add_argument(
        "--coefficients",
        type=int,
        choices=(9, 25, 49),
        default=9,
        help="SH order: 9 (eq. 9, default), 25 or 49 (bands with a non-zero cosine term)",
    )
    sh.add_argument(
        "--lights", type=int, default=0, help="extract this many cap lights first (0..32)"
    )
    sh.add_argument(
        "--threshold", type=float, default=1.0, help="light threshold in mean luminances"
    )
    sh.add_argument("--height", type=int, help="box-filter the map to this many rows first")
    sh.add_argument(
        "--cube", type=int, help="project a 6xNxN cube resampled from the map (N = this)"
    )
    sh.add_argument(
        "--check",
        action="store_true",
        help="irradiance error against brute force over the same samples (2000 random normals)",
    )
    sh.add_argument("--json", action="store_true", help="machine-readable output")

    _add_bake_parser(sub)

    figure = sub.add_parser("figure", help="render a figure of a seed paper")
    figure.add_argument(
        "name",
        choices=(
            "kautz-grid",
            "kautz-seams",
            "hwconv-distortion",
            "banks-slices",
            "rsibr-warp",
            "pem-offmanifold",
            "pem-maps",
        ),
        help="kautz-grid: seed 000 Figure 6 (b x f_lambda); kautz-seams: Figure 4, "
        "box vs cross-face mip chain at b = 9.4, with the seam measurement; "
        "hwconv-distortion: seed 004 Figure 3, a paraboloid kernel's distortion on the "
        "sphere (no GL; the scene options are ignored); rsibr-warp: seed 002 Figure 4, "
        "the three source maps, their warps into the camera's frame and the generated map; "
        "pem-offmanifold: seed 003 Figures 6-7, layered PEM, sphere at infinity and static EM "
        "against a ray trace midway between baked views and 10 and 20 degrees above the arc; "
        "pem-maps: seed 003 Figure 5, the nearest view's inferred maps per model and level",
    )
    _add_scene_options(figure)
    _add_param_option(figure)
    figure.add_argument("--camera", help="AZIMUTH,ELEVATION,DISTANCE in degrees and scene units")
    figure.add_argument("--size", default="192x192", help="one panel, WIDTHxHEIGHT")
    figure.add_argument("-o", "--output", required=True, help="OUT.png")
    return parser


def _add_bake_parser(sub) -> None:
    bake = sub.add_parser(
        "bake",
        help="offline bakes: rsibr radiance sphere maps (seed 002), pem per-view EMs (seed 003)",
    )
    bake.add_argument("kind", choices=("rsibr", "pem"), help="what to bake")
    bake.add_argument("--env", help="rsibr: lat-long environment (.exr or .hdr), required")
    bake.add_argument("--scene", help="pem: shipped scene name (room) or a TOML scene file")
    bake.add_argument("--brdf", default="phong", help="rsibr: phong, lambertian or carpaint")
    _add_param_option(bake)
    bake.add_argument(
        "--size", type=int, help="rsibr: map edge in texels (64); pem: trace resolution R (256)"
    )
    bake.add_argument(
        "--views", type=int, help="rsibr: 12 (icosahedron) or 42; pem: views on the arc (100)"
    )
    bake.add_argument("--step", type=float, help="pem: degrees between views (default 1)")
    bake.add_argument(
        "--samples",
        type=int,
        help="rsibr: GPU importance samples per lobe (256); pem: rays per pixel (4)",
    )
    bake.add_argument("--em-size", type=int, help="pem: cube face edge of the EMs (default 64)")
    bake.add_argument(
        "--elevations",
        type=int,
        default=1,
        help="pem: rows of a 2D view grid, --elevation-step apart from the scene camera's (1: arc)",
    )
    bake.add_argument(
        "--elevation-step", type=float, default=5.0, help="pem: degrees between grid rows (5)"
    )
    bake.add_argument(
        "--tie",
        type=float,
        help="pem: weight μ of the coarse-to-fine MIP ties (default 1e-3; larger: coarse levels "
        "nearer the decimated finest, steadier at small playback sizes, docs/pem)",
    )
    bake.add_argument(
        "--lookups",
        choices=("auto", "gl", "cpu"),
        default="auto",
        help="pem: build A from the playback shader's own lookups on GL (auto: when a context "
        "can be made) or from pixel-centre rays on the CPU",
    )
    bake.add_argument(
        "--workers", type=int, help="pem: local processes (default one per core; 0 in-process)"
    )
    cluster = bake.add_mutually_exclusive_group()
    cluster.add_argument(
        "--dask",
        dest="scheduler",
        action="store_const",
        const="local",
        help="pem: bake on a local Dask cluster (2 worker processes) instead of the pool",
    )
    cluster.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="pem: bake on the Dask scheduler at ADDRESS (tcp://host:8786), or 'local'",
    )
    bake.add_argument(
        "--device", choices=("auto", "gpu", "cpu"), default="auto", help="auto: GPU, else CPU"
    )
    bake.add_argument("-o", "--output", required=True, help="FILE.rsibr or FILE.pem")


def _add_prefilter_parser(sub) -> None:
    prefilter = sub.add_parser(
        "prefilter", help="prefilter an environment on the CPU (seed 004 §4, §5.1) to EXR"
    )
    prefilter.add_argument("--env", required=True, help="lat-long environment (.exr or .hdr)")
    prefilter.add_argument(
        "--kernel",
        choices=("diffuse", "phong", "lobe"),
        default="phong",
        help="diffuse k_d/π<n,l>, normalised Phong (N+1)/2π<r,l>^N, or a tabulated lobe p(<r,l>)",
    )
    prefilter.add_argument("--exponent", type=float, help="Phong exponent N > 0 (phong only)")
    prefilter.add_argument("--lobe", help="lobe table: CSV of (cosine, value) rows (lobe only)")
    prefilter.add_argument("--kd", type=float, default=1.0, help="diffuse albedo k_d (diffuse)")
    prefilter.add_argument(
        "--algo",
        choices=("brute", "hierarchical", "spectral"),
        default=None,
        help="method (default: hierarchical; with --chain spectral, or the GPU chain with "
        "--device gpu); spectral (--chain only, on the CPU): the Phong brute force by rows and "
        "azimuthal frequencies of the lat-long source, the fast CPU chain",
    )
    prefilter.add_argument(
        "--param",
        choices=("paraboloid", "cube", "latlong"),
        default="paraboloid",
        help="target (paraboloid: front | back; cube: horizontal cross; latlong: S x 2S)",
    )
    prefilter.add_argument("--size", type=int, default=128, help="face edge (lat-long: height)")
    prefilter.add_argument("--border", type=int, default=0, help="paraboloid border in texels")
    prefilter.add_argument(
        "--threshold",
        type=float,
        default=0.001,
        help="hierarchical: the largest error accepted per unit of a node's radiance when "
        "its filter is evaluated once for the node, in (0, 1) (seed 004: 0.001)",
    )
    prefilter.add_argument(
        "--source-height", type=int, help="box-filter the source to this many rows first"
    )
    prefilter.add_argument("--threads", type=int, help="worker threads (default: every core)")
    prefilter.add_argument(
        "--chain",
        action="store_true",
        help="a Phong cube mip chain for engines, N = 2^(scale*g + bias) per level "
        "(-o OUT.dds: DX10 RGBA16F cube with mips; OUT.exr: a cross per level), "
        "plus OUT.sh.json (9 SH coefficients)",
    )
    prefilter.add_argument("--levels", type=int, default=8, help="--chain: mip levels")
    prefilter.add_argument("--gloss-scale", type=float, default=10.0, help="--chain: scale")
    prefilter.add_argument("--gloss-bias", type=float, default=1.0, help="--chain: bias")
    prefilter.add_argument(
        "--check",
        action="store_true",
        help="--chain: every level against the brute force at its exponent (sampled texels)",
    )
    prefilter.add_argument(
        "--device",
        choices=("auto", "gpu", "cpu"),
        default="auto",
        help="--chain: gpu filters on the GPU (filtered importance sampling); with --algo "
        "brute|hierarchical, auto (default) does so when a GL context can be made, else the CPU; "
        "without --algo, auto and cpu take the spectral chain on the CPU",
    )
    prefilter.add_argument(
        "--samples",
        type=int,
        default=256,
        help="--chain on the GPU: importance samples per texel of level 0, doubled per level "
        "(default 256)",
    )
    prefilter.add_argument("-o", "--output", required=True, help="OUT.exr (--chain: or OUT.dds)")


def _open_file(args: argparse.Namespace) -> None:
    """``envstudio view FILE``: FILE becomes ``--env``, ``--mesh`` or ``--scene`` by its suffix.

    Raises
    ------
    InputFileError
        FILE does not exist.
    ParameterError
        FILE is of no kind the viewer opens, or the option it stands for is also given.
    """
    from pathlib import Path

    from envstudio.io.images import HDR_SUFFIXES
    from envstudio.io.meshes import MESH_SUFFIXES

    path = Path(args.file)
    suffix = path.suffix.lower()
    if suffix in HDR_SUFFIXES:
        option = "env"
    elif suffix in MESH_SUFFIXES:
        option = "mesh"
    elif suffix == ".toml":
        option = "scene"
    else:
        kinds = ", ".join((*HDR_SUFFIXES, *MESH_SUFFIXES, ".toml"))
        raise ParameterError(f"view {args.file}: expected a file of one of {kinds}")
    if not path.is_file():
        raise InputFileError(f"{args.file}: no such file")
    if getattr(args, option) is not None:
        raise ParameterError(f"view {args.file}: --{option} is given too; give one of them")
    setattr(args, option, str(path))


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit status.

    SIGTERM is handled like Ctrl-C, so a killed ``compare`` or ``bench
    --converge --resume`` saves its reference accumulation before it exits.
    """
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    argv = _file_means_view(list(sys.argv[1:] if argv is None else argv))
    try:
        args = build_parser().parse_args(argv)
        command = args.command or "view"
        if args.command is None:
            args = build_parser().parse_args(["view", *argv])
        if command == "doctor":  # before the commands' imports, which may be what is missing
            from envstudio.doctor import run_doctor

            return run_doctor()
        if command == "view" and args.file:
            _open_file(args)
        from envstudio import commands

        return getattr(commands, f"run_{command.replace('-', '_')}")(args) or 0
    except ContextError as exc:  # no GL (or no display): what is missing, and who says more
        print(f"envstudio: error: {exc} (`envstudio doctor` checks this machine)", file=sys.stderr)
        return exc.exit_code
    except UserError as exc:
        print(f"envstudio: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("envstudio: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `envstudio methods | head`: the reader left; say nothing more
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1


def _file_means_view(argv: list[str]) -> list[str]:
    """``envstudio FILE.exr`` is ``envstudio view FILE.exr`` (what a file manager runs)."""
    if not argv or argv[0].startswith("-"):
        return argv
    subcommands = next(
        a.choices for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)
    )
    if argv[0] in subcommands:
        return argv
    from pathlib import Path

    from envstudio.io.images import HDR_SUFFIXES
    from envstudio.io.meshes import MESH_SUFFIXES

    if Path(argv[0]).suffix.lower() in (*HDR_SUFFIXES, *MESH_SUFFIXES, ".toml"):
        return ["view", *argv]
    return argv


if __name__ == "__main__":
    sys.exit(main())
