"""Measuring a shown result (about 0.1 s of CPU at grid 512) never holds up a newer request: it
stops at its next step when one waits, keeps the steps it did, and an idle app still ends with
the metrics of what it shows. Ordered events, not wall time: the measuring's first step is held
until the test has made its next request."""

from __future__ import annotations

import threading

import pytest
from PySide6.QtCore import Qt

from leafstudio.core import evaluate
from leafstudio.core import result as core_result
from leafstudio.core.pipeline import Cancelled, Pipeline
from leafstudio.gui.model.session import Session
from leafstudio.gui.qt.worker import PIPELINE, Worker
from leafstudio.model import Leaf, Params
from leafstudio.sources.demos import demo
from tests.gui.builders import FAST

from .conftest import WAIT_MS

DIRECT = Qt.ConnectionType.DirectConnection  # logged on the worker's thread, in order


class HeldMeasuring:
    """Logs "measuring" at the first and the last step of every measuring (the distance search
    and the curvature summary); the first distance search waits until `submitted` is set."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch, events: list) -> None:
        self.events, self.started, self.submitted = events, threading.Event(), threading.Event()
        distances, curvature = evaluate.point_to_mesh_distance, core_result.curvature_summary

        def first_step(mesh, points):
            events.append("measuring")
            if not self.started.is_set():
                self.started.set()
                self.submitted.wait(WAIT_MS / 1000)
            return distances(mesh, points)

        def last_step(mesh):
            events.append("measuring")
            return curvature(mesh)

        monkeypatch.setattr(evaluate, "point_to_mesh_distance", first_step)
        monkeypatch.setattr(core_result, "curvature_summary", last_step)


@pytest.fixture
def worker():
    w = Worker()
    yield w
    w.shutdown()
    w.join(WAIT_MS / 1000)  # no job outlives the test (nor logs once its output is closed)


@pytest.mark.parametrize("interrupt", [True, False], ids=["typed-value", "slider-drag"])
def test_a_request_made_while_measuring_starts_before_the_measuring_goes_on(
    worker, qtbot, monkeypatch, interrupt
):
    events: list = []
    held = HeldMeasuring(monkeypatch, events)
    worker.stage_started.connect(
        lambda kind, job_id, name: kind == PIPELINE and events.append(job_id), DIRECT
    )
    leaf = demo("nested")
    worker.submit_pipeline(leaf, FAST)
    assert held.started.wait(WAIT_MS / 1000)  # the first result is being measured
    events.append("submitted")
    second = worker.submit_pipeline(leaf, FAST.with_(k=4), interrupt=interrupt)
    held.submitted.set()
    qtbot.waitUntil(lambda: second in events, timeout=WAIT_MS)
    after = events[events.index("submitted") + 1 :]
    assert after[0] == second  # the new request started before any more measuring
    qtbot.waitUntil(worker.is_idle, timeout=WAIT_MS)


def test_measuring_stopped_between_steps_goes_on_from_where_it_stopped(monkeypatch):
    result = Pipeline(demo("nested")).run(FAST)
    calls: list[int] = []
    distances = evaluate.point_to_mesh_distance
    monkeypatch.setattr(
        evaluate, "point_to_mesh_distance", lambda m, p: calls.append(1) or distances(m, p)
    )
    with pytest.raises(Cancelled):
        result.measure(should_stop=lambda: True)
    assert calls == [1] and not result.measured
    metrics = result.metrics
    assert calls == [1]  # the step already done is not done again
    assert result.measured
    fresh = Pipeline(demo("nested")).run(FAST).metrics
    assert metrics == fresh


def test_an_idle_app_ends_with_the_metrics_of_what_it_shows(worker, qtbot, monkeypatch):
    """The request that stopped the measuring fails: the result shown is measured after all,
    and the panel's figures are that result's."""
    events: list = []
    held = HeldMeasuring(monkeypatch, events)
    session = Session(worker.submit_pipeline, FAST)
    worker.yielded.connect(lambda kind, job_id, outcome: session.accept_result(outcome))
    worker.failed.connect(lambda kind, job_id, exc: session.accept_failure(job_id, exc))
    measured: list[int] = []
    worker.done.connect(
        lambda kind, job_id, _s: session.accept_measured(job_id) and measured.append(job_id)
    )
    first = session.new_document(demo("nested"), title="nested")
    assert held.started.wait(WAIT_MS / 1000)
    line = Leaf(boundary=[[t, 2 * t, 0] for t in range(10)])  # fails: one line
    second = session.new_document(line, title="a line", params=Params(grid=32))
    held.submitted.set()
    qtbot.waitUntil(lambda: worker.is_idle() and session.message != "", timeout=WAIT_MS)
    assert second > first and "one line" in session.message
    assert session.shown_id == first
    qtbot.waitUntil(lambda: measured == [first], timeout=WAIT_MS)
    assert session.shown.measured_id == session.shown_id


def test_metrics_of_a_result_no_longer_shown_never_reach_the_panel():
    """A result's measuring that ends after a newer result is shown is not taken for it."""
    session = Session(lambda leaf, params, interrupt: 0)
    older, newer = _outcome(1), _outcome(2)
    assert session.accept_result(older) is True
    assert session.accept_result(newer) is True
    assert session.accept_measured(1) is False
    assert session.shown.measured_id == 0
    assert session.accept_measured(2) is True


def _outcome(request_id: int):
    """An outcome as the worker makes it, for the nested demo at a small grid."""
    from leafstudio.gui.qt.worker import Outcome, Request

    leaf = demo("nested")
    result = Pipeline(leaf).run(FAST)
    return Outcome(Request(request_id, leaf, FAST, True), result, {})


def test_in_the_window_a_failed_request_leaves_the_shown_result_measured(
    window, qtbot, monkeypatch
):
    """A new document that fails arrives while the shown result is measured: the measuring
    gives way, then finishes; the panel shows that result's figures, and the status line keeps
    the failure's message as it is."""
    held = HeldMeasuring(monkeypatch, [])
    window.panel.k.setValue(5)
    qtbot.waitUntil(held.started.is_set, timeout=WAIT_MS)  # K = 5 is drawn, and measured
    shown = window.session.shown_id
    line = Leaf(boundary=[[t, 2 * t, 0] for t in range(10)])
    window.session.new_document(line, title="a line")
    held.submitted.set()
    qtbot.waitUntil(
        lambda: window.worker.is_idle() and window.session.shown.measured_id == shown,
        timeout=WAIT_MS,
    )
    assert window.session.shown_id == shown and window.session.result.params.k == 5
    assert (
        window.status_text.text().startswith("Failed:") and "one line" in window.status_text.text()
    )
    assert "measurements" not in window.status_text.text()
    rows = {
        item.child(j).text(0): item.child(j).text(1)
        for item in (window.measurements.topLevelItem(i) for i in range(3))
        for j in range(item.childCount())
    }
    assert rows["K"] == "5"  # the panel holds the shown result's figures
