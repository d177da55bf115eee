"""Worker processes kept for the batch tests (the `warm_pools` fixture, tests/conftest.py):
each batch runs on workers started once per pytest process, not spawned and imported anew per
batch or per file.

A spawned worker imports numpy, numba and the pipeline and loads the compiled kernels before its
first row: 4-8 s per batch on this 2-core machine, most of a small batch's time. The fixture
replaces the batch's LocalPool by WarmPool, which is LocalPool itself (the same compile check,
spawn context, initializer, SIGINT handling, job submission and outcome) except that its
ProcessPoolExecutor is kept across the session's batches, one per worker count. Rows and jobs still
cross a process boundary and run in pinned workers. Tests whose point is a fresh or dying process
(a killed batch, a plain script, the console script) do not use it.
"""

from __future__ import annotations

import importlib
from concurrent.futures import Future, ProcessPoolExecutor
from typing import ClassVar

import pytest

from leafstudio.batch.executors import LocalPool
from leafstudio.batch.plan import Job

# the module, not `ls.batch`, the function that shadows the package's name on `leafstudio`
batch_run = importlib.import_module("leafstudio.batch.run")


class WarmPool(LocalPool):
    """LocalPool on a pool of spawned workers kept in `pools` (by worker count) after close."""

    pools: ClassVar[dict[int, ProcessPoolExecutor]] = {}

    def _new_pool(self) -> ProcessPoolExecutor:
        kept = self.pools.get(self.workers)
        if kept is None or kept is getattr(self, "_pool", None):  # none yet, or it broke
            kept = self.pools[self.workers] = super()._new_pool()
        self._submitted: list[Future] = []
        return kept

    def submit(self, job: Job) -> Future:
        future = super().submit(job)
        self._submitted.append(future)
        return future

    def close(self) -> None:
        """As LocalPool.close, without ending the workers: what was not started is cancelled,
        what runs is waited for."""
        for future in self._submitted:
            future.cancel()
        for future in self._submitted:
            if not future.cancelled():
                future.exception()  # waits; its outcome was the batch's business


def use_warm_pools(monkeypatch: pytest.MonkeyPatch, pools: dict[int, ProcessPoolExecutor]) -> None:
    """Until `monkeypatch` is undone, batches run on the worker processes kept in `pools`."""
    monkeypatch.setattr(WarmPool, "pools", pools)
    monkeypatch.setattr(batch_run, "LocalPool", WarmPool)
