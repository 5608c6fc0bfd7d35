"""Work that blocks (loading a file) announced in the status line before it runs.

A job submitted during a frame is listed as busy in that frame's status line
and runs at the start of the next frame, so the user sees what the pause is
for. A :class:`~envstudio.errors.UserError` from a job becomes the status
line's error; the state the job would have replaced stays as it was.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from envstudio.errors import UserError
from envstudio.ui.status import StatusLine


@dataclass
class _Job:
    label: str
    work: Callable[[], None]
    shown: bool = False


class DeferredWork:
    """A queue of jobs run one frame after they were announced.

    Parameters
    ----------
    status
        Where the busy line and errors go.
    """

    def __init__(self, status: StatusLine):
        self._status = status
        self._jobs: list[_Job] = []

    def submit(self, label: str, work: Callable[[], None]) -> None:
        """Queue ``work``; ``label`` says what it does ("loading forest.exr")."""
        self._jobs.append(_Job(label, work))
        self._status.busy_text = ", ".join(job.label for job in self._jobs)

    def run_due(self) -> None:
        """Run the jobs that have been announced in a drawn frame (call at frame start)."""
        due = [job for job in self._jobs if job.shown]
        self._jobs = [job for job in self._jobs if not job.shown]
        for job in due:
            try:
                job.work()
            except UserError as exc:
                self._status.error(str(exc))
        self._status.busy_text = ", ".join(job.label for job in self._jobs) or None

    def mark_shown(self) -> None:
        """Record that the busy line naming every queued job was drawn (call after drawing)."""
        for job in self._jobs:
            job.shown = True
