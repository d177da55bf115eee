"""BLAS on one thread while leafstudio computes (_shared/blas.py), the earlier limit given back."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

import leafstudio as ls
import leafstudio.core.correct as correct
from leafstudio.workflows import open_scan


def blas_threads() -> set[int]:
    return {pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"}


def threads_seen(monkeypatch, module, name: str) -> list[set[int]]:
    """The BLAS thread counts `module.name` is called under, one set per call, from now on."""
    seen: list[set[int]] = []
    function = getattr(module, name)

    def spy(*args, **kwargs):
        seen.append(blas_threads())
        return function(*args, **kwargs)

    monkeypatch.setattr(module, name, spy)
    return seen


@pytest.fixture
def two_threads():
    """BLAS allowed two threads (the suite's workers run with one: tests/conftest.py)."""
    with threadpool_limits(2, user_api="blas"):
        if blas_threads() != {2}:
            pytest.skip("this machine's BLAS runs on fewer than two threads")
        yield


def test_a_reconstruction_solves_on_one_blas_thread_and_gives_the_limit_back(
    two_threads, monkeypatch
):
    seen = threads_seen(monkeypatch, correct, "fit_correction")
    ls.reconstruct(ls.demo("nested"), ls.Params(grid=32))
    assert seen and all(threads == {1} for threads in seen)
    assert blas_threads() == {2}


def test_opening_a_scan_extracts_on_one_blas_thread(two_threads, monkeypatch, tmp_path):
    import leafstudio.workflows as workflows

    seen = threads_seen(monkeypatch, workflows, "extract_leaf")
    rng = np.random.default_rng(0)
    xy = rng.uniform(-1, 1, (6000, 2)) * [1, 0.4]
    xy = xy[xy[:, 0] ** 2 + (xy[:, 1] / 0.4) ** 2 < 1]
    path = tmp_path / "scan.xyz"
    np.savetxt(path, np.column_stack([xy, 0.05 * np.exp(-((xy[:, 1] / 0.05) ** 2))]))
    open_scan(path)
    assert seen == [{1}] and blas_threads() == {2}


def test_the_apps_lanes_compute_on_one_blas_thread(two_threads, monkeypatch):
    """A command (the app's `gui` too) runs under one BLAS thread, set on the main thread: a
    lane's own limit would do nothing (threadpoolctl lets one thread set OpenBLAS's)."""
    import leafstudio.cli as cli

    seen = threads_seen(monkeypatch, correct, "fit_correction")

    def lane_command(args) -> int:  # as the app does: the pipeline runs on a worker lane
        lane = threading.Thread(target=ls.reconstruct, args=(ls.demo("nested"), ls.Params(grid=32)))
        lane.start()
        lane.join(60)
        return 0

    monkeypatch.setitem(cli.COMMANDS, "demo", lane_command)
    assert cli.main(["demo", "nested", "-o", "unused.csv"]) == 0
    assert seen and all(threads == {1} for threads in seen)
    assert blas_threads() == {2}
