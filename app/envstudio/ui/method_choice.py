"""The method on show, and the session's methods as the viewer uses them.

A method gets its saved parameter values the first time the viewer uses it,
and the frame budget that keeps a progressive method from stalling the UI.
"""

from __future__ import annotations

import sys

from envstudio.engine.method import Method
from envstudio.engine.registry import available_methods, ground_truth_class
from envstudio.engine.session import RenderSession
from envstudio.errors import ParameterError, UserError
from envstudio.measure.matching import match_through
from envstudio.ui.compare_panel import CompareState
from envstudio.ui.status import StatusLine
from envstudio.ui.viewer_state import restore_values

PROGRESSIVE_BUDGET_MS = 40.0
"""Milliseconds of progressive accumulation (the reference) per frame, so the UI stays live."""


class MethodChoice:
    """Which method is on show, and the viewer's access to every method.

    Parameters
    ----------
    session
        The session owning the methods' instances.
    saved_values
        Method name → {parameter: value} read from the settings.
    named
        Method named on the command line (None: the one last shown).
    last_shown
        Method shown last (ignored if no longer available; None: the first).
    compare
        Whether picking a method keeps the previous one's look (glossiness matching).
    status
        Where rejected saved values and failed picks are reported.
    """

    def __init__(
        self,
        session: RenderSession,
        saved_values: dict[str, dict],
        named: str | None,
        last_shown: str | None,
        compare: CompareState,
        status: StatusLine,
    ):
        self.session = session
        self.compare = compare
        self.status = status
        self.available = available_methods()
        """Method name → class, in the order the number keys pick them."""
        self.truth = _ground_truth_name()
        """The ground truth's name, whose Phong exponent every match goes through (or None)."""
        self.used: set[str] = set()
        """Methods given their saved values (their values are saved on exit)."""
        self._saved_values = saved_values
        last = last_shown if last_shown in self.available else None
        self.name = named or last or next(iter(self.available))
        """The method on show."""

    def method(self, name: str) -> Method:
        """The session's method ``name``: saved parameter values on first use, the frame budget."""
        if name not in self.used:
            problems = self.restore(name)
            for problem in problems:
                print(f"envstudio: warning: {problem}", file=sys.stderr)
            if problems:
                self.status.error("\n".join(problems))
        method = self.session.method(name)
        # progressive methods work within the budget, whichever way they were first reached
        method.frame_budget_ms = PROGRESSIVE_BUDGET_MS
        return method

    def restore(self, name: str) -> list[str]:
        """Give method ``name`` its saved parameter values; returns what was rejected."""
        self.used.add(name)
        saved = self._saved_values.get(name, {})
        problems = restore_values(self.session.method(name).values, saved)
        return [f"settings: {name}: {problem}" for problem in problems]

    def hub(self) -> Method | None:
        """The ground truth, whose Phong exponent every match goes through (None: none)."""
        return self.method(self.truth) if self.truth else None

    def select(self, name: str) -> None:
        """Show method ``name`` (with the look of the previous one when matching is on)."""
        previous = self.method(self.name)
        chosen = self.method(name)
        try:
            chosen.prepare(self.session.gpu_scene)
        except UserError as exc:  # e.g. a bake for another scene: keep the method on show
            self.status.error(f"{name}: {exc}")
            return
        if self.compare.match and chosen is not previous:
            lines = match_through([chosen], previous, self.hub(), self.session.gpu_scene.cube_size)
            self.compare.match_note = lines.get(name)
        self.name = name

    def cycle(self, first: bool) -> None:
        """``--cycle-methods``: the next method (unless ``first``), printed on stdout."""
        names = list(self.available)
        if not first:
            following = names[(names.index(self.name) + 1) % len(names)]
            if following == self.name:
                return
            self.select(following)
        print(f"envstudio: method {self.name}", flush=True)


def _ground_truth_name() -> str | None:
    try:
        return ground_truth_class().name
    except ParameterError:  # no plugin declares one: the grid shows no PSNR / FLIP
        return None
