"""Big files and long work in the window: it never waits for them (behaviour, not timings; the
figures are benchmarks/bench_gui.py's)."""

from __future__ import annotations

import json
import threading

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QApplication

from leafstudio.gui.model import opening, scans
from leafstudio.gui.qt.viewport import MINIMUM_SIZE
from tests.gui.builders import six_column_scan, write_points

from .conftest import WAIT_MS, close_window


def test_closing_does_not_wait_for_a_job_that_cannot_stop(window, qtbot):
    started, release, ended = threading.Event(), threading.Event(), threading.Event()

    def long_step() -> None:  # a compiled kernel or a file read: it never checks should_stop
        started.set()
        release.wait(5)  # the old close waited up to 10 s for it
        ended.set()

    window.worker.start("open", long_step)
    assert started.wait(10)
    close_window(window)
    assert not ended.is_set()  # closed while the job still runs: not joined
    release.set()
    assert ended.wait(10)


def measured(qtbot, window) -> None:
    qtbot.waitUntil(lambda: bool(window.measurements_panel.sections), timeout=WAIT_MS)


def test_ctrl_c_copies_the_whole_table(window, qtbot):
    measured(qtbot, window)
    tree = window.measurements
    tree.setFocus()
    tree.setCurrentItem(tree.topLevelItem(0).child(0))  # a cell: Ctrl+C copied only it
    QApplication.clipboard().clear()
    qtbot.keyClick(tree, Qt.Key.Key_C, Qt.KeyboardModifier.ControlModifier)
    text = QApplication.clipboard().text()
    titles = [tree.topLevelItem(i).text(0) for i in range(tree.topLevelItemCount())]
    assert len(titles) >= 3 and all(title in text.splitlines() for title in titles)
    assert "Area\t" in text and text == window.measurements_panel.text()


def test_section_titles_span_the_panel_and_save_writes_the_table(window, qtbot, tmp_path):
    measured(qtbot, window)
    tree = window.measurements
    section = tree.topLevelItem(1)
    assert section.isFirstColumnSpanned() and section.toolTip(0) == section.text(0)
    assert window.measurements_panel.save(str(tmp_path / "m.json"))
    table = json.loads((tmp_path / "m.json").read_text(encoding="utf-8"))
    assert section.text(0) in table
    assert not window.measurements_panel.save(str(tmp_path / "m.txt"))  # said in a box
    assert window.last_error_box is not None and "m.txt" in window.last_error_box.text()


def test_a_wide_dock_leaves_the_view_its_width(window, qtbot):
    dock, sketch = window.docks["Measurements"], window.docks["Sketch"]
    window.resizeDocks([dock], [2000], Qt.Orientation.Horizontal)
    qtbot.wait(50)
    left_for_the_view = window.width() - dock.width() - sketch.width()
    assert left_for_the_view >= MINIMUM_SIZE[0] > 300


def test_open_returns_at_once_and_cancel_stops_the_read(window, qtbot, monkeypatch, tmp_path):
    release, reached = threading.Event(), threading.Event()
    after_read: list[str] = []
    real_open = opening.open_file

    def slow_open(path):  # a big file: the read takes long
        reached.set()
        release.wait(20)
        return real_open(path)

    def layers_of(opened):  # what read_document would do next, were it not cancelled
        after_read.append("layers")
        return None

    monkeypatch.setattr(opening, "open_file", slow_open)
    monkeypatch.setattr(scans, "scan_data", layers_of)
    path = write_points(tmp_path / "scan.txt", six_column_scan())
    before = window.session.state
    job = window.open_path(path)
    assert not job.finished and window.busy.isVisible()  # returned while the file is read
    assert reached.wait(10)
    qtbot.mouseClick(window.busy.button, Qt.MouseButton.LeftButton)
    assert job.cancelled and not window.busy.isVisible()
    assert window.status_text.text() == "Opening cancelled"
    release.set()
    qtbot.waitUntil(window.worker.is_idle, timeout=WAIT_MS)
    qtbot.wait(50)
    assert after_read == []  # stopped at its next step: the scan's layers were never made
    assert window.session.state is before and window.opened_name == "scan.txt"
    assert "scan.txt" not in window.windowTitle()


def test_the_busy_bar_shows_the_read_fraction_and_cancel_stops_the_first_run(
    window, qtbot, monkeypatch, tmp_path
):
    """Issue 24, build item 4: a read showed a busy bar, never a fraction; and the bar went away
    once the file was read, so the first reconstruction (long for a big file or a cold kernel
    cache) could not be cancelled."""
    import numpy as np

    from leafstudio._shared import inputs
    from leafstudio.gui.qt import worker as worker_module

    monkeypatch.setattr(inputs, "BLOCK_CHARS", 4096)
    started, stopped = threading.Event(), threading.Event()

    class SlowPipeline(worker_module.Pipeline):
        def run(self, params, on_stage=None, should_stop=None):  # the file's first run
            started.set()
            while not should_stop():
                threading.Event().wait(0.01)
            stopped.set()
            raise worker_module.Cancelled

    t = np.linspace(0, 2 * np.pi, 1000, endpoint=False)
    path = tmp_path / "leaf.csv"
    np.savetxt(path, np.column_stack([np.cos(t), 0.4 * np.sin(t), 0 * t]), delimiter=",")
    heard: list = []
    window.session.open_progress.connect(lambda *told: heard.append(told))
    before, shown = window.session.state, window.session.result
    monkeypatch.setattr(worker_module, "Pipeline", SlowPipeline)
    window.open_path(str(path))
    qtbot.waitUntil(started.is_set, timeout=WAIT_MS)  # read, then its first run began
    qtbot.waitUntil(lambda: heard and heard[-1] == (None, "reconstructing"), timeout=WAIT_MS)
    fractions = [f for f, doing in heard if doing == "reading"]
    assert len(fractions) >= 5 and fractions[-1] == 1.0  # through the worker's signal
    assert window.busy.isVisible() and "reconstructing" in window.busy.seconds.text()
    qtbot.mouseClick(window.busy.button, Qt.MouseButton.LeftButton)
    assert stopped.wait(10)  # the run stopped at its next check
    assert not window.busy.isVisible() and window.status_text.text() == "Opening cancelled"
    assert window.session.state is before and window.session.result is shown
    qtbot.waitUntil(window.worker.is_idle, timeout=WAIT_MS)
    window.busy.start("x")
    window.busy.progress(0.25, "reading")
    assert window.busy.bar.maximum() == 1000 and window.busy.bar.value() == 250
    assert window.busy.seconds.text().startswith("reading 25%")
    window.busy.stop()
