"""``envstudio bake rsibr``: seed 002's radiance sphere maps baked to a ``.rsibr`` file.

Bad input (unknown BRDF or parameter, a value out of range, a size or view count
that is not allowed, a missing environment or output folder) is refused with one
line before any work. The file is written through io.atomic only when every map
is done, so an interrupted bake leaves nothing under the output name.
"""

from __future__ import annotations

import argparse
import sys
import time

from tqdm import tqdm

from envstudio.core.parameters import parse_assignments
from envstudio.errors import ContextError
from envstudio.io.atomic import check_output_path
from envstudio.io.images import read_environment
from envstudio.methods.rsibr.bake import bake as rb
from envstudio.methods.rsibr.bake.brdfs import brdf
from envstudio.plugin import Bake, ParameterError

__all__ = ["BAKE", "MAX_SIZE", "add_bake_arguments", "bake_environment", "run_bake_rsibr"]

#: Largest map edge accepted.
MAX_SIZE = 2048


def bake_environment(
    environment, name: str, values: dict, size: int, views: int, samples: int, device: str, bar
) -> rb.RsibrBake:
    """Bake on the GPU (``gpu``, or ``auto`` when a context can be made), else the CPU.

    Parameters
    ----------
    environment : (h, 2h, 3) float32
        Lat-long radiance.
    name, values, size, views, samples
        As ``envstudio bake rsibr`` takes them.
    device
        ``auto``, ``gpu`` or ``cpu``.
    bar
        A tqdm bar over texels (its ``total`` is set here).
    """
    bar.total = size * size * views
    if device != "cpu":
        try:
            return _bake_gpu(environment, name, values, size, views, samples, bar.update)
        except ContextError:
            if device == "gpu":
                raise
            bar.write("envstudio: no GL context, baking on the CPU")
    return rb.bake_cpu(environment, name, values, size, views, bar.update)


def _bake_gpu(environment, name, values, size, views, samples, progress) -> rb.RsibrBake:
    from envstudio.envmap.conversions import latlong_to_cube, upload_latlong
    from envstudio.gpu.context import create_headless_context
    from envstudio.gpu.programs import ProgramLibrary
    from envstudio.methods.rsibr.gpu_bake import bake_gpu

    ctx = create_headless_context()
    programs = ProgramLibrary(ctx)
    try:
        latlong = upload_latlong(ctx, environment)
        cube = latlong_to_cube(ctx, programs, latlong, max(64, min(512, environment.shape[0])))
        key = rb.environment_key(environment)
        return bake_gpu(ctx, programs, cube, key, name, values, size, views, samples, progress)
    finally:
        programs.release()
        ctx.release()


def add_bake_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``envstudio bake rsibr``."""
    parser.add_argument("--env", help="lat-long environment (.exr or .hdr), required")
    parser.add_argument(
        "--max-env-width",
        type=int,
        metavar="W",
        help="box-filter the environment to at most W texels wide as it is read",
    )
    parser.add_argument("--brdf", default="phong", help="phong, lambertian or carpaint")
    parser.add_argument("--size", type=int, default=64, help="map edge in texels (64)")
    parser.add_argument("--views", type=int, default=12, help="12 (icosahedron) or 42")
    parser.add_argument(
        "--samples", type=int, default=256, help="GPU importance samples per lobe (256)"
    )
    parser.add_argument(
        "--device", choices=("auto", "gpu", "cpu"), default="auto", help="auto: GPU, else CPU"
    )


def run_bake_rsibr(args: argparse.Namespace) -> int:
    """Check the arguments, bake with a progress bar, write the file, print one line."""
    if args.env is None:
        raise ParameterError("bake rsibr: --env is required (a lat-long .exr or .hdr)")
    values = brdf(args.brdf).values(parse_assignments(args.param))
    if not 4 <= args.size <= MAX_SIZE:
        raise ParameterError(f"--size {args.size}: expected a map edge in [4, {MAX_SIZE}]")
    if not 1 <= args.samples <= 65536:
        raise ParameterError(f"--samples {args.samples}: expected an integer in [1, 65536]")
    rb.geodesic_views(args.views)  # refuses a count it does not know
    out = check_output_path(args.output, (".rsibr",))
    environment = read_environment(args.env, args.max_env_width)
    start = time.perf_counter()
    with tqdm(
        unit="texel",
        unit_scale=True,
        desc=f"rsibr {args.brdf}",
        leave=False,
        disable=not sys.stderr.isatty(),
    ) as bar:
        bake = bake_environment(
            environment, args.brdf, values, args.size, args.views, args.samples, args.device, bar
        )
    seconds = time.perf_counter() - start
    rb.save_bake(out, bake)
    print(
        f"{out}: {len(bake.views)} {bake.brdf} maps of {bake.size}² ({bake.warp} warp) "
        f"baked on the {bake.device.upper()} in {seconds:.1f} s"
    )
    return 0


BAKE = Bake(
    "rsibr",
    "seed 002's radiance sphere maps of an environment at the icosahedron's views, to FILE.rsibr",
    run_bake_rsibr,
    add_bake_arguments,
)
