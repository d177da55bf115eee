"""Suite-wide: an internal error of the command line (exit 1, "internal error") fails the test,
and tests that need open3d skip without it.

Bad input must end as one line and exit 2 (LeafError), by design; the catch-all in cli.main is the
last resort. Here it re-raises, so the test fails with the bug's own traceback. A test of the
catch-all itself is marked `@pytest.mark.internal_error`.

open3d is an extra (`pip install 'leafstudio[open3d]'`, about 1 GiB): ball pivoting, the Poisson
comparison, .pcd scans, levels of detail. A test of those is marked `@pytest.mark.open3d` and
skips where it is not installed; check with it hidden, as a machine without it has it:
`PYTHONPATH=DIR:. python -m pytest`, DIR holding a sitecustomize.py that sets
`sys.modules["open3d"] = None`.

With pytest-xdist (`./dev test`), the numba kernels are compiled once in the controller before
the workers start: on a cold cache each worker's first reconstruction would otherwise compile
them at the same time as the other's (four compiling processes on two cores), and the GUI tests'
waits for a window's first result ran out. The controller also lends the workers a folder they
share for the run (SHARED: a real scan extracted by one worker is read by the other). Each worker
runs its BLAS (OpenBLAS) on one thread, its child processes too: two workers' two-thread pools on
two cores wait on each other (tests/core/test_correct.py beside another process: 52 s -> 35 s).
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import tempfile
from collections.abc import Iterator
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from concurrent.futures import ProcessPoolExecutor

SHARED = "LEAFSTUDIO_TEST_SHARED"  # the run's shared folder (tests/leaves.extracted_scan)
HAS_OPEN3D = importlib.util.find_spec("open3d") is not None  # found, not imported: seconds


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "internal_error: the test exercises cli's catch-all for bugs on purpose"
    )
    config.addinivalue_line(
        "markers", "open3d: the test needs open3d (the open3d extra); skipped without it"
    )
    if hasattr(config, "workerinput"):
        _one_blas_thread()
    if _xdist_controller(config):
        from leafstudio.core.kernels import TABLES, compile_kernels

        # every table, in parallel processes; nothing to do on a warm cache (the stamps)
        compile_kernels(tables=TABLES)
        os.environ[SHARED] = tempfile.mkdtemp(prefix="leafstudio-tests-")  # workers inherit it


def pytest_unconfigure(config: pytest.Config) -> None:
    if _xdist_controller(config) and SHARED in os.environ:
        shutil.rmtree(os.environ.pop(SHARED), ignore_errors=True)


def _one_blas_thread() -> None:
    """Limit this process's BLAS to one thread, and its children's (they read the variables)."""
    for variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(variable, "1")
    import numpy  # noqa: F401  (loads the BLAS that threadpoolctl limits)
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)


def _xdist_controller(config: pytest.Config) -> bool:
    """This process hands tests to xdist workers (`-n N`), which start after it is configured."""
    workers = getattr(config.option, "numprocesses", None)
    return bool(workers) and not hasattr(config, "workerinput")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if HAS_OPEN3D:
        return
    skip = pytest.mark.skip(reason="open3d is not installed (pip install 'leafstudio[open3d]')")
    for item in items:
        if item.get_closest_marker("open3d") is not None:
            item.add_marker(skip)


@pytest.fixture(autouse=True)
def _internal_error_fails(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch):
    if request.node.get_closest_marker("internal_error") is not None:
        yield
        return
    import leafstudio.cli as cli

    def fail(exc: Exception, debug: bool) -> int:
        raise AssertionError(f"internal error in the command line: {exc!r}") from exc

    monkeypatch.setattr(cli, "_internal_error", fail)
    yield


@pytest.fixture(scope="session")
def kept_pools() -> Iterator[dict[int, ProcessPoolExecutor]]:
    """The kept worker pools (tests/batch/pools.py), shared by every test of a pytest process
    that runs a batch, ended after its last test: each file started its own before (5-10 s of
    spawned imports each), and a test outside tests/batch its own again."""
    pools: dict[int, ProcessPoolExecutor] = {}
    yield pools
    for pool in pools.values():
        pool.shutdown(wait=True, cancel_futures=True)


@pytest.fixture
def warm_pools(monkeypatch: pytest.MonkeyPatch, kept_pools) -> None:
    """Batches in this test run on the session's kept worker processes (tests/batch/pools.py)."""
    from tests.batch.pools import use_warm_pools

    use_warm_pools(monkeypatch, kept_pools)
