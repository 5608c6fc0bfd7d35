"""``envstudio diffuse``: each method's own diffuse term against brute-force irradiance."""

from __future__ import annotations

import argparse
import json

from envstudio.commands.common import add_param_option
from envstudio.engine.hooks import Command
from envstudio.errors import ParameterError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Methods, environments, parameters, size, JSON."""
    parser.add_argument(
        "--methods",
        help="comma-separated methods with k_d and f_λ (default: all of them but the reference)",
    )
    parser.add_argument(
        "--envs",
        help="comma-separated shipped environment names or .exr/.hdr files (default: all shipped)",
    )
    add_param_option(parser)
    parser.add_argument("--size", default="64x64", help="WIDTHxHEIGHT of the sphere image")
    parser.add_argument("--json", action="store_true", help="machine-readable output")


def run(args: argparse.Namespace) -> int:
    """Render the sphere with k_d = 1 and 0 per method and environment; print the errors."""
    from envstudio.engine.registry import available_methods, ground_truth_class, method_class
    from envstudio.io.images import read_environment
    from envstudio.io.scene_file import shipped_environments
    from envstudio.io.scene_setup import parse_size
    from envstudio.measure.compare import plan_parameters
    from envstudio.measure.diffuse_check import CORE_COSINE, diffuse_errors
    from envstudio.scene.environment import Environment

    size = parse_size(args.size)
    if args.methods:
        names = [n.strip() for n in args.methods.split(",") if n.strip()]
        classes = [method_class(n) for n in names]
    else:
        truth = ground_truth_class().name
        classes = [c for n, c in available_methods().items() if n != truth]
    classes = [c for c in classes if {"kd", "fresnel"} <= {p.name for p in c.parameters}]
    if not classes:
        raise ParameterError(f"--methods {args.methods}: none of them declares kd and fresnel")
    plan = plan_parameters(classes, args.param)
    shipped = shipped_environments()
    envs = [e.strip() for e in args.envs.split(",")] if args.envs else list(shipped)
    rows = []
    for env in envs:
        path = shipped.get(env, env)
        environment = Environment(read_environment(path))
        runs = [(c.name, [f"{k}={v}" for k, v in plan.methods[c.name].items()]) for c in classes]
        for result in diffuse_errors(environment, runs, size):
            rows.append({"environment": str(env), **result.__dict__})
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    print(
        f"diffuse part (1 - F) E(n)/pi against brute-force irradiance, sphere at {args.size}, "
        f"n.v > {CORE_COSINE}, luminance"
    )
    print(f"{'environment':<16} {'method':<8} {'mean %':>8} {'max %':>8} {'bias %':>8}  settings")
    for row in rows:
        print(
            f"{row['environment']:<16} {row['method']:<8} {100 * row['mean']:>8.3f} "
            f"{100 * row['maximum']:>8.2f} {100 * row['bias']:>+8.3f}  {row['settings']}"
        )
    return 0


COMMAND = Command(
    "diffuse",
    "each method's diffuse term against brute-force irradiance on a sphere",
    run,
    add_arguments,
)
