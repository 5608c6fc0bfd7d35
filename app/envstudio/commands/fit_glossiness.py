"""``envstudio fit-glossiness``: refit the LOD bias ↔ Phong exponent match (seed 000 §6)."""

from __future__ import annotations

import argparse
import json
import sys

from envstudio.engine.hooks import Command
from envstudio.errors import ParameterError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Output, sizes, environments, directions."""
    parser.add_argument("--out", help="JSON file to write (default: the package's stored fit)")
    parser.add_argument(
        "--sizes", type=int, nargs="+", help="cube face sizes, powers of two (default 64..512)"
    )
    parser.add_argument("--environments", nargs="+", metavar="NAME", help="shipped maps to fit")
    parser.add_argument("--directions", type=int, help="reflection directions per environment")


def run(args: argparse.Namespace) -> int:
    """Fit with a progress bar, write the JSON atomically, print the model."""
    from tqdm import tqdm

    from envstudio.io.atomic import check_output_path, write_text_atomic
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


COMMAND = Command(
    "fit-glossiness",
    "refit the LOD bias <-> Phong exponent match (minutes; CPU only)",
    run,
    add_arguments,
)
