"""``envstudio methods [--json | --markdown]``: every method in the declared order, with its
parameters (or, ``--markdown``, the README's table of methods)."""

from __future__ import annotations

import argparse
import json

from envstudio.engine.hooks import Command


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """``--json`` or ``--markdown``."""
    output = parser.add_mutually_exclusive_group()
    output.add_argument("--json", action="store_true", help="machine-readable output")
    output.add_argument(
        "--markdown",
        action="store_true",
        help="one table row a method: name, title, paper, reflectance model, summary (the "
        "README's list of methods is this output)",
    )


def markdown_table(described: list[dict]) -> str:
    """The methods as a Markdown table, one row each in the declared order.

    Parameters
    ----------
    described : list of dict
        :meth:`Method.describe` of each method.
    """
    rows = [
        "| method | title | paper | reflectance | what it does |",
        "| --- | --- | --- | --- | --- |",
    ]
    for entry in described:
        cells = [f"`{entry['name']}`", entry["title"], entry["paper"], entry["reflectance"]]
        cells.append(entry["summary"])
        rows.append("| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |")
    return "\n".join(rows)


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
    if args.markdown:
        print(markdown_table(described))
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
