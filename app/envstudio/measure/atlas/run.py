"""Measure an atlas: the cells not yet in its folder, then its outputs."""

from __future__ import annotations

import sys
from pathlib import Path

from tqdm import tqdm

from envstudio.measure.atlas.entries import free_file
from envstudio.measure.atlas.grid import AtlasGrid
from envstudio.measure.atlas.lock import LOCK_NAME, folder_lock
from envstudio.measure.atlas.page import OUTPUTS, write_outputs
from envstudio.measure.atlas.pool import run_tasks
from envstudio.measure.atlas.store import AtlasStore
from envstudio.measure.atlas.validate import check_grid

__all__ = ["AtlasResult", "run_atlas"]


class AtlasResult:
    """What :func:`run_atlas` did.

    Attributes
    ----------
    rows : list of dict
        Every cell of the grid.
    measured : int
        The cells measured in this run.
    failed : int
        The cells whose row says why they failed.
    notes : list of str
        One line per entry of the folder set aside or measured again.
    """

    def __init__(self, rows: list[dict], measured: int, failed: int, notes: list[str]):
        self.rows = rows
        self.measured = measured
        self.failed = failed
        self.notes = notes


def run_atlas(
    grid: AtlasGrid,
    folder: str | Path,
    jobs: int = 1,
    scheduler: str | None = None,
    force: bool = False,
    progress: bool = False,
) -> AtlasResult:
    """Measure the grid's missing cells into ``folder`` and write its outputs.

    Parameters
    ----------
    grid
        The cells.
    folder
        The output folder; cells already there (same settings) are not measured again,
        so an interrupted atlas resumes and a wider one costs only its new cells.
    jobs
        Worker processes (pool.run_tasks).
    scheduler
        ``local`` or a Dask scheduler address, else None.
    force
        Measure again in a folder of other settings (AtlasStore).
    progress
        One bar on stderr: method cells done and left, and the time left.

    Raises
    ------
    ParameterError, InputFileError
        A grid some cell of which cannot be measured (validate.check_grid; nothing is
        written then), or a folder of other settings.
    OutputFileError
        Another atlas is measuring into ``folder`` (lock.folder_lock).
    """
    check_grid(grid)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    notes: list[str] = []
    free_file(folder / LOCK_NAME, notes)
    with folder_lock(folder):
        store = AtlasStore(folder, grid, force)
        tasks = []
        for cell in grid.scene_cells():
            missing = store.missing(cell, grid.methods)
            if missing:
                tasks.append((cell, missing, grid.settings, store.folder_of(cell)))
        # scenes that differ only in N share their Banks reference (measure/exact_cache.py):
        # one N at a time over the scenes, so parallel workers do not both evaluate it
        tasks.sort(key=lambda task: task[0].exponent)
        total = sum(len(t[1]) for t in tasks)
        measured = 0
        bar = tqdm(total=total, desc="atlas", unit="cell", file=sys.stderr, disable=not progress)
        with bar:
            for task, rows in run_tasks(tasks, jobs, scheduler):
                store.add(task[0], rows)
                measured += len(rows)
                bar.update(len(rows))
        rows = [
            row
            for cell in grid.scene_cells()
            for row in store.rows(cell)
            if row["method"] in grid.methods
        ]
        for name in OUTPUTS:
            free_file(folder / name, store.notes)
        write_outputs(grid, rows, folder)
    failed = sum(1 for r in rows if r.get("error"))
    return AtlasResult(rows, measured, failed, notes + store.notes)
