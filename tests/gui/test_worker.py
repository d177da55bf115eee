"""The worker on its own: latest request wins, failures are reported, nothing runs on the
main thread."""

from __future__ import annotations

import threading

import pytest

from leafstudio.demos import demo
from leafstudio.gui.worker import PipelineWorker
from leafstudio.model import Leaf, Params

from .conftest import FAST, WAIT_MS


@pytest.fixture
def worker():
    w = PipelineWorker()
    yield w
    w.shutdown()


def test_newer_requests_replace_older_ones(worker, qtbot):
    leaf = demo("nested")
    finished, stages = [], []
    worker.finished.connect(finished.append)
    worker.stage_started.connect(lambda rid, name: stages.append(rid))
    for k in range(1, 13):  # twelve requests while the first is still running
        worker.submit(leaf, FAST.with_(k=k))
    qtbot.waitUntil(lambda: worker.is_idle() and bool(finished), timeout=WAIT_MS)
    assert finished[-1].result.params.k == 12
    assert finished[-1].request.id == worker.last_id
    assert len(finished) <= 2  # at most the first (if it beat the others) and the last
    assert len(set(stages)) <= 3  # only a few requests ever started a stage
    assert all(o.thread != threading.main_thread().ident for o in finished)


def test_a_live_request_lets_the_running_one_finish(worker, qtbot):
    leaf = demo("nested")
    finished = []
    worker.finished.connect(finished.append)
    started = []
    worker.stage_started.connect(lambda rid, name: started.append(rid))
    first = worker.submit(leaf, FAST.with_(k=2))
    qtbot.waitUntil(lambda: first in started, timeout=WAIT_MS)
    worker.submit(leaf, FAST.with_(k=3), interrupt=False)
    qtbot.waitUntil(lambda: worker.is_idle() and len(finished) == 2, timeout=WAIT_MS)
    assert [o.result.params.k for o in finished] == [2, 3]


def test_a_failure_is_reported_with_its_message(worker, qtbot):
    line = Leaf(boundary=[[t, 2 * t, 0] for t in range(10)])
    with qtbot.waitSignal(worker.failed, timeout=WAIT_MS) as failure:
        request = worker.submit(line, Params(grid=32))
    assert failure.args[0] == request
    assert "one line" in failure.args[1]


def test_the_pipeline_cache_is_kept_between_runs_of_one_leaf(worker, qtbot):
    leaf = demo("nested")
    with qtbot.waitSignal(worker.finished, timeout=WAIT_MS):
        worker.submit(leaf, FAST)
    outcomes, measured = [], []
    worker.finished.connect(outcomes.append)
    worker.measured.connect(lambda rid, seconds: measured.append(rid))
    request = worker.submit(leaf, FAST.with_(k=5))
    qtbot.waitUntil(lambda: request in measured, timeout=WAIT_MS)
    outcome = outcomes[-1]
    assert "frame" not in outcome.result.ran and "layers" in outcome.timings
    assert "veins" in outcome.result.metrics  # computed on the worker thread
