"""Run independent chunks of prefilter work on a thread pool, with a progress bar.

NumPy's ufuncs and BLAS release the GIL on large arrays, so threads over
chunks of target texels use every core without copying the source map into
processes. BLAS is held to one thread meanwhile (threadpoolctl): the chunks
are the parallelism, and OpenBLAS's own threads, spinning on a busy machine,
made its small products up to a hundred times slower. A Ctrl-C in the main
thread cancels the chunks not yet started; the one or two running finish (each
is small) and the KeyboardInterrupt goes on.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

from threadpoolctl import threadpool_limits
from tqdm import tqdm

__all__ = ["default_threads", "run_chunks"]


def default_threads() -> int:
    """Worker threads: the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def run_chunks(
    work: Callable[[int], None],
    costs: Sequence[int],
    *,
    threads: int | None = None,
    progress: bool = False,
    desc: str = "prefilter",
) -> None:
    """Call ``work(k)`` for every chunk k, on ``threads`` threads.

    Parameters
    ----------
    work
        Does chunk k and stores its result itself (chunks must not overlap).
    costs
        Target texels of each chunk, for the progress bar's count and time left.
    threads
        Worker threads (default :func:`default_threads`); 1 runs in the caller's thread.
    progress
        Show a tqdm bar on stderr (with the time left).
    desc
        The bar's label.
    """
    threads = threads or default_threads()
    with threadpool_limits(limits=1, user_api="blas"):
        _run(work, costs, threads, progress, desc)


def _run(work, costs, threads: int, progress: bool, desc: str) -> None:
    with tqdm(
        total=int(sum(costs)),
        desc=desc,
        unit="texel",
        unit_scale=True,
        file=sys.stderr,
        disable=not progress,
        smoothing=0.1,
    ) as bar:
        if threads == 1:
            for k, cost in enumerate(costs):
                work(k)
                bar.update(cost)
            return
        pool = ThreadPoolExecutor(max_workers=threads)
        try:
            pending = {pool.submit(work, k): cost for k, cost in enumerate(costs)}
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in done:
                    future.result()
                    bar.update(pending.pop(future))
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
