"""Work spread over processes or machines: a Dask client (``--dask``, ``--scheduler``) and
the environment a rendering worker starts with."""

from __future__ import annotations

import os

__all__ = ["LLVMPIPE_THREADS", "SCHEDULER_TIMEOUT_S", "dask_client", "worker_environ"]

#: Seconds a scheduler address has to answer.
SCHEDULER_TIMEOUT_S = 10.0
#: Mesa llvmpipe's rasteriser threads (read when a process makes its first context).
LLVMPIPE_THREADS = "LP_NUM_THREADS"


def worker_environ(workers: int) -> dict[str, str]:
    """The environment a process that renders beside ``workers - 1`` others starts with.

    llvmpipe starts one rasteriser thread per core in every process; with one worker per
    core the threads of all of them contend for the cores: the atlas at ``--jobs 2`` on two
    cores ran 8 % slower than with one thread each (studies/atlas-full/README.md). Each
    worker gets its share of the cores, at least one. Empty for a single worker and where
    ``LP_NUM_THREADS`` is set already (the user's choice wins).

    Returns
    -------
    dict of str to str
        ``{"LP_NUM_THREADS": "k"}`` or ``{}``.
    """
    if workers <= 1 or LLVMPIPE_THREADS in os.environ:
        return {}
    return {LLVMPIPE_THREADS: str(max(1, (os.cpu_count() or 1) // workers))}


def dask_client(scheduler: str, timeout: float = SCHEDULER_TIMEOUT_S, workers: int = 2):
    """(client, cluster or None): a new LocalCluster for ``"local"``, else the scheduler's.

    Parameters
    ----------
    scheduler
        ``local``, or an address such as ``tcp://host:8786``.
    timeout
        Seconds the scheduler has to answer.
    workers
        Worker processes of a LocalCluster (one thread each).

    Raises
    ------
    ParameterError
        One line: distributed is not installed, or no scheduler answered.
    """
    from envstudio.errors import ParameterError

    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover - the cluster extra is in the lock
        raise ParameterError(
            "a Dask run needs dask and distributed: pip install 'envmap-studio[cluster]'"
        ) from None
    if scheduler == "local":
        import dask

        # worker processes start with spawn (distributed's default): no fork after EGL or Embree.
        # Without distributed's MALLOC_TRIM_THRESHOLD_: setting it fixes glibc's mmap threshold,
        # so every large temporary of a solve is mapped and unmapped afresh; the PEM bake's
        # multigrid solve ran 2.7 times slower on the workers than on the pool with it
        # (studies/pem-paper-scale/README.md).
        environ = {
            "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
            # each worker's share of llvmpipe's threads, as the process pool's
            **{
                f"distributed.nanny.pre-spawn-environ.{k}": v
                for k, v in worker_environ(workers).items()
            },
        }
        with dask.config.set(environ):
            cluster = LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
            )
        return Client(cluster), cluster
    try:
        return Client(scheduler, timeout=timeout), None
    except (OSError, TimeoutError, ValueError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ParameterError(
            f"--scheduler {scheduler}: no Dask scheduler answered within {timeout:g} s ({reason})"
        ) from None
