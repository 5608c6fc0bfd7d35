"""``envstudio methods [--json]``: every method in the declared order, with its parameters."""

from __future__ import annotations

import argparse
import json

from envstudio.engine.hooks import Command


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """``--json``."""
    parser.add_argument("--json", action="store_true", help="machine-readable output")


def run(args: argparse.Namespace) -> int:
    """Print every method and its parameters (name, type, range, default, unit, help)."""
    from envstudio.engine.display import DISPLAY_PARAMETERS
    from envstudio.engine.registry import available_methods

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


COMMAND = Command("methods", "list the methods and their parameters", run, add_arguments)
