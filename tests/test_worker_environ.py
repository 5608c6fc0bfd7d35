"""Each rendering worker starts with its share of llvmpipe's threads (io.cluster.worker_environ):
in the atlas's process pool and on a local Dask cluster."""

import os

import pytest

from envstudio.io.cluster import LLVMPIPE_THREADS, dask_client, worker_environ
from envstudio.measure.atlas.pool import worker_pool


@pytest.fixture
def unset_threads(monkeypatch):
    monkeypatch.delenv(LLVMPIPE_THREADS, raising=False)
    return max(1, (os.cpu_count() or 1) // 2)


def test_a_worker_gets_its_share_of_the_cores_and_a_set_value_wins(monkeypatch, unset_threads):
    assert worker_environ(1) == {}
    assert worker_environ(2) == {LLVMPIPE_THREADS: str(unset_threads)}
    assert worker_environ(10 * (os.cpu_count() or 1)) == {LLVMPIPE_THREADS: "1"}
    monkeypatch.setenv(LLVMPIPE_THREADS, "3")
    assert worker_environ(2) == {}


def test_the_pool_s_workers_start_with_it(unset_threads):
    with worker_pool(2) as pool:
        seen = {pool.submit(os.getenv, LLVMPIPE_THREADS).result() for _ in range(4)}
    assert seen == {str(unset_threads)}
    assert LLVMPIPE_THREADS not in os.environ


def test_a_local_cluster_s_workers_start_with_it(unset_threads):
    client, cluster = dask_client("local", workers=2)
    try:
        seen = client.run(os.getenv, LLVMPIPE_THREADS)
    finally:
        client.close()
        cluster.close()
    assert sorted(seen.values()) == [str(unset_threads)] * 2
