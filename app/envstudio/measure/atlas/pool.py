"""Run the atlas's scenes: here, in worker processes, or on a Dask cluster.

Each worker renders in its own headless EGL context (a process each, started
with ``spawn``: no fork after a context or Embree exists), kept from one scene
to the next of the same environment (sessions.py). References are
cached by content in ``$ENVSTUDIO_CACHE_DIR`` (measure.ground_truth_cache),
where every worker of one machine reaches them; on a cluster of several
machines, point ``ENVSTUDIO_CACHE_DIR`` at a shared folder.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from envstudio.errors import UserError
from envstudio.io.cluster import worker_environ
from envstudio.measure.atlas.cells import failed_rows, measure_scene_cell
from envstudio.measure.atlas.grid import SceneCell
from envstudio.measure.atlas.sessions import release_kept

__all__ = ["Task", "measure_task", "run_tasks", "worker_pool"]

#: (scene, methods, grid settings, image folder).
Task = tuple[SceneCell, list[str], dict, Path]


def measure_task(task: Task) -> list[dict]:
    """Measure one scene's methods; a method that fails is measured alone and marked.

    Never raises for a failing method (bad input or a fault in its code): its rows say
    why in one line instead, and the other methods are still measured.
    """
    cell, methods, settings, folder = task
    try:
        return measure_scene_cell(cell, methods, settings, folder)
    except Exception as error:  # the atlas goes on and reports the cell
        if len(methods) == 1:
            return failed_rows(cell, methods, _one_line(error))
    rows = []
    for method in methods:  # which one failed: each alone (the references are cached)
        try:
            rows += measure_scene_cell(cell, [method], settings, folder)
        except Exception as error:
            rows += failed_rows(cell, [method], _one_line(error))
    return rows


def _one_line(error: Exception) -> str:
    """A user error's own line; any other fault as its type and first line."""
    if isinstance(error, UserError):
        return str(error)
    text = str(error).splitlines()[0] if str(error) else ""
    return f"{type(error).__name__}: {text}".rstrip(": ")


def run_tasks(
    tasks: list[Task], jobs: int = 1, scheduler: str | None = None
) -> Iterator[tuple[Task, list[dict]]]:
    """Yield (task, rows) as scenes finish: in order here, as they come elsewhere.

    Parameters
    ----------
    tasks
        The scenes to measure.
    jobs
        Worker processes (1: in this process).
    scheduler
        ``local`` for a Dask LocalCluster of ``jobs`` workers, or a scheduler address.
    """
    if scheduler is not None:
        yield from _run_dask(tasks, jobs, scheduler)
    elif jobs <= 1:
        try:
            for task in tasks:
                yield task, measure_task(task)
        finally:
            release_kept()
    else:
        with worker_pool(jobs) as pool:
            futures = {pool.submit(measure_task, task): task for task in tasks}
            try:
                for future in as_completed(futures):
                    yield futures[future], future.result()
            except BaseException:
                for future in futures:
                    future.cancel()
                raise


def worker_pool(jobs: int) -> ProcessPoolExecutor:
    """``jobs`` worker processes started with ``spawn``, each with its share of llvmpipe's
    threads (io.cluster.worker_environ) set before it makes a context."""
    context = multiprocessing.get_context("spawn")
    return ProcessPoolExecutor(
        jobs, mp_context=context, initializer=_set_environ, initargs=(worker_environ(jobs),)
    )


def _set_environ(values: dict[str, str]) -> None:
    """A worker's first step: ``values`` into its environment, before any context exists."""
    os.environ.update(values)


def _run_dask(tasks: list[Task], jobs: int, scheduler: str):
    from envstudio.io.cluster import dask_client

    client, cluster = dask_client(scheduler, workers=max(jobs, 1))
    try:
        from dask.distributed import as_completed as dask_completed

        futures = {client.submit(measure_task, task, pure=False): task for task in tasks}
        try:
            for future in dask_completed(futures):
                yield futures[future], future.result()
        except BaseException:
            client.cancel(list(futures))
            raise
        finally:  # the workers' kept sessions, on a cluster that stays; a lost worker's
            with contextlib.suppress(Exception):  # error must not hide the run's own
                client.run(release_kept)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
