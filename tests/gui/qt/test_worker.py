"""The worker on its own: newest request wins, failures come back as exception objects logged
with their traceback, side tasks run beside the pipeline, nothing runs on the main thread."""

from __future__ import annotations

import logging
import os
import sys
import threading

import pytest

from leafstudio.errors import LeafError
from leafstudio.gui.qt.worker import PIPELINE, Worker
from leafstudio.model import Leaf, Params
from leafstudio.sources.demos import demo
from tests.gui.builders import FAST

from .conftest import WAIT_MS


@pytest.fixture
def worker():
    w = Worker()
    yield w
    w.shutdown()
    w.join(WAIT_MS / 1000)  # no job outlives the test (nor logs once its output is closed)


@pytest.fixture
def app_worker(app_niceness):
    """A worker whose lanes run as nice as the app's (conftest.app_niceness)."""
    w = Worker()
    yield w
    w.shutdown()
    w.join(WAIT_MS / 1000)


def collect(worker: Worker) -> dict[str, list]:
    got: dict[str, list] = {"yielded": [], "done": [], "failed": [], "stages": []}
    worker.yielded.connect(lambda kind, jid, value: got["yielded"].append((kind, jid, value)))
    worker.done.connect(lambda kind, jid, value: got["done"].append((kind, jid, value)))
    worker.failed.connect(lambda kind, jid, exc: got["failed"].append((kind, jid, exc)))
    worker.stage_started.connect(lambda kind, jid, name: got["stages"].append(jid))
    return got


def test_newer_requests_replace_older_ones(worker, qtbot):
    leaf = demo("nested")
    got = collect(worker)
    for k in range(1, 13):  # twelve requests while the first is still running
        worker.submit_pipeline(leaf, FAST.with_(k=k))
    qtbot.waitUntil(lambda: worker.is_idle() and bool(got["yielded"]), timeout=WAIT_MS)
    outcomes = [value for _, _, value in got["yielded"]]
    assert outcomes[-1].result.params.k == 12
    assert outcomes[-1].request.id == worker.last_id
    assert len(outcomes) <= 2  # at most the first (if it beat the others) and the last
    assert len(set(got["stages"])) <= 3  # only a few requests ever started a stage
    assert all(o.thread != threading.main_thread().ident for o in outcomes)


def test_a_live_request_lets_the_running_one_finish(worker, qtbot):
    leaf = demo("nested")
    got = collect(worker)
    first = worker.submit_pipeline(leaf, FAST.with_(k=2))
    qtbot.waitUntil(lambda: first in got["stages"], timeout=WAIT_MS)
    worker.submit_pipeline(leaf, FAST.with_(k=3), interrupt=False)
    qtbot.waitUntil(lambda: worker.is_idle() and len(got["yielded"]) == 2, timeout=WAIT_MS)
    assert [o.result.params.k for _, _, o in got["yielded"]] == [2, 3]


def test_a_failure_comes_back_as_the_exception_itself(worker, qtbot):
    line = Leaf(boundary=[[t, 2 * t, 0] for t in range(10)])
    with qtbot.waitSignal(worker.failed, timeout=WAIT_MS) as failure:
        request = worker.submit_pipeline(line, Params(grid=32))
    kind, job_id, exc = failure.args
    assert (kind, job_id) == (PIPELINE, request)
    assert isinstance(exc, LeafError) and "one line" in str(exc)


def test_an_unexpected_error_is_logged_with_its_traceback(worker, qtbot, caplog):
    def broken(context, value):
        return {}[value]

    with (
        caplog.at_level(logging.ERROR, logger="leafstudio.gui"),
        qtbot.waitSignal(worker.failed, timeout=WAIT_MS) as failure,
    ):
        worker.submit("fidelity", broken, "missing")
    assert isinstance(failure.args[2], KeyError)
    record = caplog.records[-1]
    assert record.exc_info is not None and record.exc_info[0] is KeyError
    assert "broken" in caplog.text  # the traceback names the failing function


def test_side_tasks_run_while_the_pipeline_is_busy(worker, qtbot):
    leaf = demo("nested")
    release = threading.Event()
    got = collect(worker)

    def slow_stage(context, value):
        release.wait(10)
        return value

    worker.submit("poisson", slow_stage, "side")  # holds the side lane until released
    request = worker.submit_pipeline(leaf, FAST)
    qtbot.waitUntil(lambda: any(j == request for _, j, _ in got["yielded"]), timeout=WAIT_MS)
    assert not got["done"] or got["done"][-1][0] == PIPELINE  # the side task still waits
    release.set()
    qtbot.waitUntil(lambda: any(k == "poisson" for k, _, _ in got["done"]), timeout=WAIT_MS)
    qtbot.waitUntil(worker.is_idle, timeout=WAIT_MS)


def test_the_pipeline_cache_is_kept_between_runs_of_one_leaf(worker, qtbot):
    leaf = demo("nested")
    got = collect(worker)
    first = worker.submit_pipeline(leaf, FAST)
    qtbot.waitUntil(lambda: any(j == first for _, j, _ in got["done"]), timeout=WAIT_MS)
    request = worker.submit_pipeline(leaf, FAST.with_(k=5))
    qtbot.waitUntil(lambda: any(j == request for _, j, _ in got["done"]), timeout=WAIT_MS)
    outcome = got["yielded"][-1][2]
    assert "frame" not in outcome.result.ran and "layers" in outcome.timings
    assert "veins" in outcome.result.metrics  # computed on the worker thread


def test_the_same_leaf_opened_again_reruns_no_stage_and_keeps_its_own_object(worker, qtbot):
    """The cache is keyed on the leaf's coordinates: the same demo opened again (a new Leaf, as
    reopening a file gives) was reconstructed from scratch; its result still names the new
    leaf, and another leaf still runs every stage."""
    got = collect(worker)
    first = worker.submit_pipeline(demo("nested"), FAST)
    qtbot.waitUntil(lambda: any(j == first for _, j, _ in got["done"]), timeout=WAIT_MS)
    again = demo("nested")
    request = worker.submit_pipeline(again, FAST)
    qtbot.waitUntil(lambda: any(j == request for _, j, _ in got["done"]), timeout=WAIT_MS)
    outcome = got["yielded"][-1][2]
    assert outcome.result.ran == () and outcome.result.leaf is again
    other = worker.submit_pipeline(demo("parallel"), FAST)
    qtbot.waitUntil(lambda: any(j == other for _, j, _ in got["done"]), timeout=WAIT_MS)
    assert "frame" in got["yielded"][-1][2].result.ran


def test_a_job_that_fails_after_shutdown_logs_nothing(worker, caplog):
    """A job of a closed window that failed later logged its traceback into a stream that was
    gone by then (a test's captured output: "I/O operation on closed file")."""
    started, release = threading.Event(), threading.Event()

    def fails_late() -> None:
        started.set()
        release.wait(WAIT_MS / 1000)
        raise RuntimeError("failed after the window closed")

    worker.start("open", fails_late)
    assert started.wait(WAIT_MS / 1000)
    worker.shutdown()
    with caplog.at_level(logging.DEBUG, logger="leafstudio.gui"):
        release.set()
        assert worker.join(WAIT_MS / 1000)
    assert "failed after the window closed" not in caplog.text


@pytest.mark.parametrize("how", ["cancel", "close"])
def test_cancel_or_closing_during_the_first_compile_ends_it(
    worker, qtbot, monkeypatch, tmp_path, how
):
    """Cancel (or the window closing) while the first run compiles the kernels in worker
    processes ends them, where the compile ran on to its end (issue 24)."""
    from leafstudio._shared import kernelcache
    from leafstudio.core import kernels

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))  # a cold cache, filled by the workers
    one = "surface:_levenberg_marquardt"  # seconds to compile
    monkeypatch.setattr(kernels, "KERNELS", {one: kernels.KERNELS[one]})
    compiling = threading.Event()
    ended: list[set] = []
    started = kernels._Crew.join

    def join(crew, process):  # the worker process is up: the compile is under way
        started(crew, process)
        ended.append(crew.processes)
        compiling.set()

    monkeypatch.setattr(kernels._Crew, "join", join)
    got = collect(worker)
    job = worker.submit_pipeline(demo("nested"), FAST)
    assert compiling.wait(WAIT_MS / 1000)
    worker.cancel(job) if how == "cancel" else worker.shutdown()
    qtbot.waitUntil(worker.is_idle, timeout=WAIT_MS)
    if how == "close":
        assert worker.join(WAIT_MS / 1000)
    qtbot.waitUntil(lambda: not ended[0], timeout=WAIT_MS)  # the crew's process left it
    assert not list(tmp_path.rglob("*.nbi"))  # cut short: nothing compiled to the end
    assert not kernelcache.kernels_cached()
    assert not got["yielded"] and not got["failed"]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a thread's own niceness")
def test_every_lane_runs_nicer_than_the_main_thread(app_worker, app_niceness, qtbot):
    """A reconstruction or a side job must leave the cores to the window's renders (issue 24:
    a render stretched from 45 to 100-150 ms while K changed on a 2M-point scan). The app's
    niceness: the other tests run the lanes at their own (conftest.lanes_at_the_tests_priority)."""
    assert app_niceness > 0
    worker = app_worker
    main = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
    seen: dict[str, int] = {}

    def niceness(lane: str) -> None:
        seen[lane] = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())

    for kind in (PIPELINE, "fidelity", "export"):
        worker.start(kind, niceness, worker.lanes[kind])
    qtbot.waitUntil(lambda: len(seen) == 3, timeout=WAIT_MS)
    assert seen == dict.fromkeys(("pipeline", "side", "export"), min(19, main + app_niceness))
    assert os.getpriority(os.PRIO_PROCESS, threading.get_native_id()) == main
