"""A Dask client for work spread over processes or machines (``--dask``, ``--scheduler``)."""

from __future__ import annotations

__all__ = ["SCHEDULER_TIMEOUT_S", "dask_client"]

#: Seconds a scheduler address has to answer.
SCHEDULER_TIMEOUT_S = 10.0


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
        with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}):
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
