"""``envstudio prefilter`` and ``envstudio bench --prefilter``: checks, run, output.

Bad input raises ParameterError / InputFileError (one line, exit status 2) before
any work starts. The EXR is written only when the map is complete, through
io.atomic, so a Ctrl-C leaves no file (partial or temporary) behind.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from envstudio.commands.common import add_env_width_option
from envstudio.commands.map_size import default_size
from envstudio.engine.hooks import Command
from envstudio.errors import ParameterError
from envstudio.io.atomic import check_output_path, write_text_atomic
from envstudio.io.images import read_environment, write_image
from envstudio.prefilter import brute_force, hierarchical, kernels
from envstudio.prefilter.parallel import default_threads
from envstudio.prefilter.targets import target_directions, target_picture, target_shape

__all__ = [
    "COMMAND",
    "add_arguments",
    "check_memory",
    "kernel_from_args",
    "run_prefilter",
    "run_prefilter_bench",
]

#: Largest face edge: the GL_MAX_TEXTURE_SIZE of current GPUs and of llvmpipe.
MAX_SIZE = 16384
#: ``--size`` when not given (more for a paraboloid border that needs it: :func:`default_size`).
DEFAULT_SIZE = 128
#: ``--chain``'s ``--levels`` when not given, where the size holds them (else all it holds).
DEFAULT_LEVELS = 8


def kernel_from_args(args: argparse.Namespace) -> kernels.Kernel:
    """The kernel named by ``--kernel`` with its ``--exponent`` / ``--lobe`` / ``--kd``."""
    if args.kernel == "ggx":
        raise ParameterError(
            "--kernel ggx: only with --chain (one GGX roughness per level, Filament's mapping)"
        )
    if args.kernel == "phong":
        if args.exponent is None:
            raise ParameterError("--kernel phong needs --exponent N (a Phong exponent > 0)")
        return kernels.phong(args.exponent)
    if args.exponent is not None and not args.exponent > 0:
        raise ParameterError(f"--exponent {args.exponent:g}: expected a Phong exponent > 0")
    if args.kernel == "lobe":
        if not args.lobe:
            raise ParameterError("--kernel lobe needs --lobe TABLE.csv (rows: cosine, value)")
        return kernels.read_lobe_table(args.lobe)
    return kernels.diffuse(args.kd)


def check_memory(target_texels: int, source_texels: int) -> None:
    """Refuse a map that would need more memory than the machine has free.

    The estimate: the float32 target and its picture (24 B a texel), the source,
    its pyramid and float64 copies (about 100 B a texel), and per thread the
    scratch of a block of cosines (16 × source texels × 8 B).

    Raises
    ------
    ParameterError
        Naming both amounts, in MiB.
    """
    threads = os.cpu_count() or 1
    need = 24 * target_texels + 100 * source_texels + threads * 16 * 8 * source_texels
    free = _free_memory()
    if free is not None and need > free:
        raise ParameterError(
            f"--size/--source-height: this prefilter needs about {need / 2**20:.0f} MiB of memory "
            f"and {free / 2**20:.0f} MiB are free; choose a smaller --size or --source-height"
        )


def _check_shared(args: argparse.Namespace) -> None:
    """The checks a single map and a chain share: threshold, border, threads, source height."""
    if not 0.0 < args.threshold < 1.0:
        raise ParameterError(f"--threshold {args.threshold:g}: expected a number in (0, 1)")
    if args.param == "paraboloid":
        if not 0 <= args.border < args.size / 2:
            raise ParameterError(
                f"--border {args.border}: expected 0 <= border < size/2 = {args.size / 2:g}"
            )
    elif args.border:
        raise ParameterError(f"--border {args.border}: only a paraboloid target has a border")
    if args.threads is not None and not 1 <= args.threads <= 256:
        raise ParameterError(f"--threads {args.threads}: expected 1..256")
    if args.source_height is not None and args.source_height < 1:
        raise ParameterError(f"--source-height {args.source_height}: expected a positive number")


def _checked_args(args: argparse.Namespace) -> kernels.Kernel:
    args.size = default_size(args.size, args.border, DEFAULT_SIZE)
    _check_shared(args)
    if not 1 <= args.size <= MAX_SIZE:
        raise ParameterError(
            f"--size {args.size}: expected 1..{MAX_SIZE} (the largest GL texture edge)"
        )
    return kernel_from_args(args)


def _source(args: argparse.Namespace) -> np.ndarray:
    """The ``--env`` map, box-filtered to ``--source-height`` rows when given."""
    radiance = read_environment(args.env, args.max_env_width)
    if args.source_height is not None:
        if radiance.shape[0] % args.source_height:
            raise ParameterError(
                f"--source-height {args.source_height}: expected a divisor of the map's "
                f"{radiance.shape[0]} rows"
            )
        radiance = brute_force.downsample_latlong(radiance, args.source_height)
    return radiance


def run_prefilter(args: argparse.Namespace) -> int:
    """``envstudio prefilter``: one prefiltered map, written as linear EXR."""
    if args.chain:
        return run_chain(args)
    args.algo = args.algo or "hierarchical"
    if args.algo == "spectral":
        raise ParameterError("--algo spectral: only with --chain (brute or hierarchical here)")
    kernel = _checked_args(args)
    output = check_output_path(args.output)
    if output.suffix.lower() != ".exr":
        raise ParameterError(f"-o {output}: expected an .exr file name")
    radiance = _source(args)
    faces, rows, cols = target_shape(args.param, args.size)
    check_memory(faces * rows * cols, radiance.shape[0] * radiance.shape[1])
    directions = target_directions(args.param, args.size, args.border)
    progress = sys.stderr.isatty()
    start = time.perf_counter()
    if args.algo == "brute":
        maps = brute_force.prefilter(
            radiance, directions, kernel, threads=args.threads, progress=progress
        )
    else:
        maps = hierarchical.prefilter(
            radiance, directions, kernel, args.threshold, threads=args.threads, progress=progress
        )
    seconds = time.perf_counter() - start
    write_image(output, target_picture(args.param, maps))
    what = f"N = {kernel.exponent:g}" if kernel.name == "phong" else kernel.name
    print(
        f"{output}: {args.param} {faces}x{rows}x{cols} {what} from a "
        f"{radiance.shape[1]}x{radiance.shape[0]} lat-long, {args.algo} in {seconds:.2f} s"
    )
    return 0


def _check_chain_output(args: argparse.Namespace) -> tuple[Path, str]:
    """The chain's ``-o`` path and its suffix, checked against ``--pixel-format``."""
    output = check_output_path(args.output)
    suffix = output.suffix.lower()
    if suffix not in (".dds", ".exr", ".ktx2"):
        raise ParameterError(f"-o {output}: expected a .dds, .ktx2 or .exr file name")
    pixel_format = getattr(args, "pixel_format", None)
    if pixel_format is not None and suffix != ".dds":
        raise ParameterError(f"--pixel-format {pixel_format}: only for a .dds output")
    if pixel_format == "rgba8" and args.kernel == "ggx":
        raise ParameterError(
            "--kernel ggx --pixel-format rgba8: RGBA8 clamps radiance to [0, 1] and a GGX "
            "chain is HDR; use --pixel-format rgba16f (the default), .ktx2 or .exr"
        )
    return output, suffix


def run_chain(args: argparse.Namespace) -> int:
    """``envstudio prefilter --chain``: the Phong or GGX cube mip chain, its SH, the check."""
    from envstudio.core.cubemap import faces_to_cross
    from envstudio.core.sh import project_latlong_sh9
    from envstudio.io.dds import write_dds_cube
    from envstudio.prefilter.chain import chain_level_error, gloss_exponents, prefiltered_chain

    if args.param != "cube" or args.kernel not in ("phong", "ggx") or args.exponent is not None:
        raise ParameterError(
            "--chain: a Phong or GGX cube chain (--param cube, --kernel phong|ggx, no "
            "--exponent: Phong's N comes from --gloss-scale and --gloss-bias per level, "
            "GGX's alpha from the level)"
        )
    ggx = args.kernel == "ggx"
    size = args.size = DEFAULT_SIZE if args.size is None else args.size
    if size < 1 or size & (size - 1) or size > MAX_SIZE:
        raise ParameterError(f"--size {size}: --chain needs a power of two in 1..{MAX_SIZE}")
    most = size.bit_length()
    if args.levels is None:  # as many as the size holds, up to DEFAULT_LEVELS
        args.levels = min(DEFAULT_LEVELS, most)
    if not 1 <= args.levels <= most:
        raise ParameterError(f"--levels {args.levels}: expected 1..{most} for --size {size}")
    if not 0 < args.gloss_scale <= 20 or not -10 <= args.gloss_bias <= 20:
        raise ParameterError(
            f"--gloss-scale {args.gloss_scale:g} --gloss-bias {args.gloss_bias:g}: "
            "expected a scale in (0, 20] and a bias in [-10, 20]"
        )
    _check_shared(args)
    if max(gloss_exponents(args.levels, args.gloss_scale, args.gloss_bias)) > 1e5:
        raise ParameterError(
            f"--gloss-scale {args.gloss_scale:g} --gloss-bias {args.gloss_bias:g}: level 0's "
            "exponent would exceed 100000"
        )
    output, suffix = _check_chain_output(args)
    device = getattr(args, "device", "cpu")
    samples = getattr(args, "samples", 256)
    if not 1 <= samples <= 16384:
        raise ParameterError(f"--samples {samples}: expected 1..16384 importance samples")
    algo = getattr(args, "algo", None)
    if algo is None:  # the fast and accurate chain, unless the GPU is asked for
        algo = "hierarchical" if device == "gpu" else "spectral"
    spectral = algo == "spectral"
    if spectral and device == "gpu":
        raise ParameterError("--algo spectral --device gpu: the spectral chain runs on the CPU")
    if ggx and not spectral:
        raise ParameterError(
            f"--kernel ggx --algo {algo} --device {device}: the GGX chain is the spectral one "
            "on the CPU (method splitsum filters its levels on the GPU)"
        )
    if spectral:
        _check_spectral_memory(size)
    radiance = _source(args)
    check_memory(6 * size * size * 2, radiance.shape[0] * radiance.shape[1])
    ctx = None if spectral else _chain_context(device)
    start = time.perf_counter()
    if ggx:
        from envstudio.prefilter.spectral import ggx_spectral_chain

        chain = ggx_spectral_chain(
            radiance, size, args.levels, threads=args.threads or default_threads()
        )
        where = "CPU (spectral)"
    elif spectral:
        from envstudio.prefilter.spectral import spectral_chain

        chain = spectral_chain(
            radiance,
            size,
            args.levels,
            args.gloss_scale,
            args.gloss_bias,
            threads=args.threads or default_threads(),
        )
        where = "CPU (spectral)"
    elif ctx is not None:
        from envstudio.gpu.context import describe
        from envstudio.gpu.programs import ProgramLibrary
        from envstudio.prefilter.chain_gpu import gpu_prefiltered_chain

        programs = ProgramLibrary(ctx)
        try:
            chain = gpu_prefiltered_chain(
                ctx,
                programs,
                radiance,
                size,
                args.levels,
                args.gloss_scale,
                args.gloss_bias,
                samples,
            )
        finally:
            programs.release()
            where = f"GPU ({describe(ctx)}), {samples} samples at level 0"
            ctx.release()
    else:
        chain = prefiltered_chain(
            radiance,
            size,
            args.levels,
            args.gloss_scale,
            args.gloss_bias,
            args.threshold,
            threads=args.threads,
            progress=sys.stderr.isatty(),
        )
        where = "CPU (hierarchical)"
    seconds = time.perf_counter() - start
    faces = [level.faces for level in chain]
    sh9 = project_latlong_sh9(radiance)
    if suffix == ".dds":
        written = [write_dds_cube(output, faces, getattr(args, "pixel_format", None) or "rgba16f")]
    elif suffix == ".ktx2":
        from envstudio.io.ktx2 import write_ktx2_cube

        written = [write_ktx2_cube(output, faces, _chain_metadata(chain))]
    else:
        written = [
            write_image(output.with_name(f"{output.stem}_mip{k}.exr"), faces_to_cross(level.faces))
            for k, level in enumerate(chain)
        ]
    sh = {
        "environment": str(args.env),
        "order": "seed 000 eq. 9: Y0; Y1..Y3 = y, z, x; Y4, Y5, Y7 = xy, yz, xz; "
        "Y6 = 3z^2 - 1; Y8 = x^2 - y^2",
        "coefficients": sh9.tolist(),
    }
    sh_path = output.with_name(f"{output.stem}.sh.json")
    write_text_atomic(sh_path, json.dumps(sh, indent=2) + "\n")
    if getattr(args, "gltf", False):
        from envstudio.io.gltf_ibl import write_lights_image_based

        extras = {"environment": str(args.env), **_chain_metadata(chain)}
        if suffix == ".ktx2":
            extras["ktx2"] = output.name
        written.append(
            write_lights_image_based(output.with_suffix(".gltf"), sh9, faces, extras=extras)[-1]
        )
    print(
        f"{', '.join(map(str, written))}, {sh_path}: {len(chain)} levels in {seconds:.2f} s "
        f"on the {where}"
    )
    for k, level in enumerate(chain):
        what = f"alpha = {level.exponent:.4g}" if ggx else f"N = {level.exponent:.4g}"
        line = (
            f"  level {k}: {level.faces.shape[1]}² {what} "
            f"from {2 * level.source_rows}x{level.source_rows}"
        )
        if args.check and ggx and level.exponent == 0.0:
            line += ", the environment resampled (core.resample.latlong_to_cube), not filtered"
        elif args.check:
            rms, worst = chain_level_error(radiance, level)
            line += f", vs brute force: rms {100 * rms:.3f} %, max {100 * worst:.3f} % of the mean"
        print(line)
    return 0


def _chain_metadata(chain) -> dict[str, str]:
    """The chain's kernel and per-level parameter, as the KTX2 key/value data holds them."""
    values = " ".join(f"{level.exponent:.9g}" for level in chain)
    if chain[0].kernel == "ggx":
        return {
            "envstudio.kernel": "ggx (split sum, N = V = R; Karis 2013)",
            "envstudio.roughness": values,
            "envstudio.roughnessMapping": "alpha_k = (k / (K - 1))^2 (Filament), GGX alpha",
        }
    return {
        "envstudio.kernel": "phong (normalised, (N + 1)/2pi cos^N)",
        "envstudio.exponent": values,
    }


def _free_memory() -> int | None:
    """Bytes of physical memory free now, None where the system does not say."""
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def _check_spectral_memory(size: int) -> None:
    """Refuse a spectral chain whose interpolation matrices would not fit in free memory.

    Level 0's matrix has 16 entries (4 B weight, 4 B column) per texel of 6 n², the levels
    below a third more, and building one takes about as much again: some 2.5 kB per n².
    """
    need = 2560 * size * size
    free = _free_memory()
    if free is not None and need > free:
        raise ParameterError(
            f"--size {size}: the spectral chain needs about {need / 2**20:.0f} MiB of memory "
            f"and {free / 2**20:.0f} MiB are free; choose a smaller --size"
        )


def _chain_context(device: str):
    """The GL context the chain is filtered with: None for the CPU.

    ``auto`` falls back to the CPU when no context can be made; ``gpu`` raises the
    one-line ContextError instead.
    """
    if device == "cpu":
        return None
    from envstudio.errors import ContextError
    from envstudio.gpu.context import create_headless_context

    try:
        return create_headless_context()
    except ContextError:
        if device == "gpu":
            raise
        return None


def _bench_face(text: str | None) -> int:
    """``--size FACExWIDTH`` (two faces: WIDTH = 2 FACE) or ``FACE`` → the face edge."""
    text = text or "128x256"
    face, _, width = text.lower().partition("x")
    try:
        n, w = int(face), int(width or 2 * int(face))
    except ValueError:
        n, w = 0, 0
    if n < 8 or n & (n - 1) or w != 2 * n:
        raise ParameterError(
            f"--size {text}: expected FACEx(2*FACE) with FACE a power of two >= 8, e.g. 128x256"
        )
    return n


def _exponents(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        values = []
    if not values or not all(0 < v <= 1e5 for v in values):
        raise ParameterError(
            f"--exponents {text}: expected comma-separated Phong exponents in (0, 100000]"
        )
    return values


def run_prefilter_bench(args: argparse.Namespace) -> int:
    """``envstudio bench --prefilter``: seed 004 §5.1's table, JSON and the plot."""
    from envstudio.prefilter.bench import (
        SWEEP_FACES,
        format_prefilter_report,
        run_prefilter_bench,
        write_scaling_plot,
    )
    from envstudio.resources import asset_root

    if getattr(args, "chain", False):
        return _run_chain_bench(args)
    face = _bench_face(args.size)
    exponents = _exponents(args.exponents)
    json_out = check_output_path(args.json_out, (".json",)) if args.json_out else None
    env = args.env or str(asset_root() / "hdr" / "studio.exr")
    radiance = read_environment(env, args.max_env_width)
    sweep = SWEEP_FACES if json_out else ()
    for n in (face, *sweep):
        if radiance.shape[0] % n:
            raise ParameterError(
                f"--env {env}: {radiance.shape[0]} rows cannot be box-filtered to {n} "
                f"(needs a multiple of {max(face, *sweep)})"
            )

    def say(line: str) -> None:
        if sys.stderr.isatty():
            print(line, file=sys.stderr)

    report = run_prefilter_bench(radiance, face, exponents, sweep=sweep, progress=say)
    report["environment"] = env
    print(format_prefilter_report(report))
    if json_out:
        write_text_atomic(json_out, json.dumps(report, indent=2))
        plot = write_scaling_plot(report, json_out.with_suffix(".png"))
        print(f"{json_out}, {plot}")
    return 0


def _run_chain_bench(args: argparse.Namespace) -> int:
    """``envstudio bench --prefilter --chain``: the spectral CPU and GPU chains, times, errors."""
    from envstudio.prefilter.bench import format_chain_report, run_chain_bench
    from envstudio.resources import asset_root

    json_out = check_output_path(args.json_out, (".json",)) if args.json_out else None
    env = args.env or str(asset_root() / "hdr" / "studio.exr")
    report = run_chain_bench(read_environment(env, args.max_env_width))
    report["environment"] = env
    print(format_chain_report(report))
    if json_out:
        write_text_atomic(json_out, json.dumps(report, indent=2))
        print(json_out)
    return 0


def add_arguments(prefilter: argparse.ArgumentParser) -> None:
    """Source, kernel, algorithm, target, size, the chain's options, output."""
    prefilter.add_argument("--env", required=True, help="lat-long environment (.exr or .hdr)")
    add_env_width_option(prefilter)
    prefilter.add_argument(
        "--kernel",
        choices=("diffuse", "phong", "lobe", "ggx"),
        default="phong",
        help="diffuse k_d/π<n,l>, normalised Phong (N+1)/2π<r,l>^N, a tabulated lobe p(<r,l>), "
        "or (--chain only) the split-sum GGX lobe, alpha_k = (k/(K-1))^2 per level",
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
    prefilter.add_argument(
        "--size",
        type=int,
        help=f"face edge (lat-long: height; default {DEFAULT_SIZE}, or 2 * border + 2 for a "
        "wider paraboloid --border)",
    )
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
        help="a cube mip chain for engines, Phong N = 2^(scale*g + bias) per level or "
        "(--kernel ggx) GGX alpha_k = (k/(K-1))^2 (-o OUT.ktx2: KTX 2.0 RGBA16F cube with "
        "mips; OUT.dds: DX10 cube with mips; OUT.exr: a cross per level), "
        "plus OUT.sh.json (9 SH coefficients)",
    )
    prefilter.add_argument(
        "--levels",
        type=int,
        help=f"--chain: mip levels (default {DEFAULT_LEVELS}, or as many as --size holds: "
        "log2(size) + 1)",
    )
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
    prefilter.add_argument(
        "--pixel-format",
        choices=("rgba16f", "rgba8"),
        default=None,
        help="--chain -o OUT.dds: half floats (default) or bytes clamped to [0, 1] (LDR)",
    )
    prefilter.add_argument(
        "--gltf",
        action="store_true",
        help="--chain: also OUT.gltf, a glTF EXT_lights_image_based light (SH irradiance, "
        "RGBD PNG faces per level)",
    )
    prefilter.add_argument(
        "-o", "--output", required=True, help="OUT.exr (--chain: or OUT.dds, OUT.ktx2)"
    )


COMMAND = Command(
    "prefilter",
    "prefilter an environment on the CPU (seed 004 §4, §5.1) to EXR",
    run_prefilter,
    add_arguments,
)
