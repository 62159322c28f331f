"""Sweeps past one machine, on a Dask cluster.

A sweep maps :func:`thymio_bt.run.sweep.run_job` over jobs through anything with
``imap_unordered(fn, jobs)``. Ray's ``ray.util.multiprocessing.Pool`` has that method already; Dask
needs this small adapter over ``Client.map`` (``pip install 'thymio-bt[dask]'``). Workers load a
mission once and keep it, keyed on the content of its files and settings, so a file edited between
two sweeps is read again.

To use it (a cluster's scheduler is needed, so this is not run as a doctest: ``tests/test_distributed.py``
runs a sweep on a local cluster)::

    from distributed import Client
    result = sweep("maze_bonus", runs=10_000, executor=DaskExecutor(Client("tcp://scheduler:8786")))
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from typing import Any

from thymio_bt.run.sweep import Job, SweepRow


class DaskExecutor:
    """Runs a sweep's jobs on a ``distributed.Client``'s workers, yielding results as they finish."""

    def __init__(self, client: Any) -> None:
        self.client = client

    def imap_unordered(self, fn: Callable[[Job], SweepRow], jobs: Iterable[Job]) -> Iterator[SweepRow]:
        """``fn(job)`` of every job, computed on the cluster, in the order they finish."""
        from distributed import as_completed

        futures = self.client.map(fn, list(jobs), pure=False)
        try:
            for future in as_completed(futures):
                yield future.result()
        finally:
            self.client.cancel(futures)  # an interrupted sweep leaves no work queued on the cluster
