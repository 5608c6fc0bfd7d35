"""``envstudio doctor``: what this machine has for envmap-studio, and what is missing."""

from __future__ import annotations

import argparse

from envstudio.engine.hooks import Command


def run(args: argparse.Namespace) -> int:
    """Print the report; 0 when nothing is missing."""
    from envstudio.doctor import run_doctor

    return run_doctor()


COMMAND = Command(
    "doctor",
    "what this machine has (GL, EGL, window, packages, folders) and what is missing",
    run,
)
