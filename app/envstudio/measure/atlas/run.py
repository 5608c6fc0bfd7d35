"""Measure an atlas: the cells not yet in its folder, then its outputs."""

from __future__ import annotations

import sys
from pathlib import Path

from tqdm import tqdm

from envstudio.measure.atlas.cells import resolve_env, resolve_mesh
from envstudio.measure.atlas.grid import AtlasGrid
from envstudio.measure.atlas.page import write_outputs
from envstudio.measure.atlas.pool import run_tasks
from envstudio.measure.atlas.store import AtlasStore

__all__ = ["AtlasResult", "run_atlas"]


class AtlasResult:
    """What :func:`run_atlas` did: every row, and how many cells it measured or found failed."""

    def __init__(self, rows: list[dict], measured: int, failed: int):
        self.rows = rows
        self.measured = measured
        self.failed = failed


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
    ParameterError
        An unknown environment, shape or method, or a folder of other settings.
    """
    for env in grid.envs:
        resolve_env(env)
    for mesh in grid.meshes:
        resolve_mesh(mesh)
    from envstudio.measure.compare import method_classes

    method_classes(list(grid.methods))
    store = AtlasStore(Path(folder), grid, force)
    tasks = []
    for cell in grid.scene_cells():
        missing = store.missing(cell, grid.methods)
        if missing:
            tasks.append((cell, missing, grid.settings, store.folder_of(cell)))
    total = sum(len(t[1]) for t in tasks)
    measured = 0
    with tqdm(total=total, desc="atlas", unit="cell", file=sys.stderr, disable=not progress) as bar:
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
    write_outputs(grid, rows, Path(folder))
    return AtlasResult(rows, measured, sum(1 for r in rows if r.get("error")))
