"""Batch tests' fixtures: worker processes kept for a test file (tests/batch/pools.py)."""

from __future__ import annotations

from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor

import pytest

from tests.batch.pools import use_warm_pools


@pytest.fixture(scope="module")
def module_pools() -> Iterator[dict[int, ProcessPoolExecutor]]:
    """The module's kept worker pools, ended after its last test."""
    pools: dict[int, ProcessPoolExecutor] = {}
    yield pools
    for pool in pools.values():
        pool.shutdown(wait=True, cancel_futures=True)


@pytest.fixture
def warm_pools(monkeypatch, module_pools) -> None:
    """Batches in this test run on the module's kept worker processes (see the module doc)."""
    use_warm_pools(monkeypatch, module_pools)
