"""Batch tests' fixtures: worker processes kept for the session (tests/batch/pools.py)."""

from __future__ import annotations

from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor

import pytest

from tests.batch.pools import use_warm_pools


@pytest.fixture(scope="session")
def kept_pools() -> Iterator[dict[int, ProcessPoolExecutor]]:
    """The kept worker pools, shared by the batch test files a pytest process runs, ended after
    its last test: each file started its own before (5-10 s of spawned imports each)."""
    pools: dict[int, ProcessPoolExecutor] = {}
    yield pools
    for pool in pools.values():
        pool.shutdown(wait=True, cancel_futures=True)


@pytest.fixture
def warm_pools(monkeypatch, kept_pools) -> None:
    """Batches in this test run on the session's kept worker processes (tests/batch/pools.py)."""
    use_warm_pools(monkeypatch, kept_pools)
