"""The sketch editor between a new document and its sketch: a loaded leaf's sketch is derived
from its first result, and until then the editor showed the previous document's sketch. A click
in that gap edited the old sketch and committed it onto the new document, replacing its leaf."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt

from leafstudio.gui.model.session import Session
from leafstudio.gui.model.sketch_model import BOUNDARY, Sketch
from leafstudio.model import Leaf
from leafstudio.sources.demos import demo
from leafstudio.sources.files import save_leaf
from tests.gui.builders import Runner, six_column_scan, write_points
from tests.gui.model.test_session import FAST

from .conftest import wait_result
from .test_sketch import click


def never_done(window, monkeypatch) -> None:
    """Reconstructions are queued but never finish: the gap before the first result lasts.

    Each takes the worker's next id, as a real request would, and runs nothing: the session
    stays in step with the worker, so that after the test (`monkeypatch` gives the session its
    way to the worker back) the lent window is reset, not built again (LentWindow.lend). An id
    out of the worker's sequence (10**9) left the session ignoring every later answer (an open
    ignores the requests up to the last one's id)."""
    worker = window.worker

    def queued(leaf, params, interrupt) -> int:
        with worker._wake:  # the worker's own lock on its ids
            worker._last_id += 1
            return worker._last_id

    monkeypatch.setattr(window.session, "submit", queued)


def open_parallel(window, qtbot, tmp_path, how: str) -> None:
    if how == "demo":
        window.open_demo("parallel")
    else:
        path = tmp_path / "parallel.leaf.json"
        save_leaf(demo("parallel"), path)
        assert window.open_path(str(path))  # read off the main thread
        qtbot.waitUntil(lambda: window.session.state.path == str(path), timeout=30_000)


@pytest.mark.parametrize("how", ["demo", "file"])
def test_a_click_before_the_new_leafs_sketch_arrives_leaves_the_new_document_alone(
    window, qtbot, tmp_path, monkeypatch, how
):
    session, view = window.session, window.editor.view
    old = view.sketch
    assert len(old.boundary) >= 3
    never_done(window, monkeypatch)
    open_parallel(window, qtbot, tmp_path, how)
    opened = session.state
    assert opened.sketch is None
    for xy in (old.boundary[0], old.boundary.mean(axis=0), (0.3, 0.1)):
        click(qtbot, view, xy)
    assert session.state is opened and session.history.count() == 0  # no old sketch committed
    assert view.sketch is not old and len(view.sketch.boundary) == 0  # the old one is gone
    assert not window.editor.isEnabled() and window.editor.waiting.isVisible()


def test_the_editor_takes_the_new_leafs_sketch_with_its_first_result(window, qtbot, tmp_path):
    session, view = window.session, window.editor.view
    open_parallel(window, qtbot, tmp_path, "file")
    opened = session.state
    wait_result(qtbot, window, lambda o: o.result.leaf is opened.leaf)
    assert window.editor.isEnabled() and not window.editor.waiting.isVisible()
    assert view.sketch is session.derived and len(view.sketch.boundary) >= 3
    tip = int(np.argmax(view.sketch.boundary[:, 0]))
    click(qtbot, view, view.sketch.boundary[tip] + (0.05, 0.0))  # an edit of the new leaf
    assert session.history.count() == 1 and session.state.sketch is not None
    assert len(session.state.sketch.boundary) == len(session.derived.boundary) + 1
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)


def test_a_new_sketch_is_editable_at_once_and_a_failed_open_gives_back_the_old_sketch(
    window, qtbot, tmp_path, monkeypatch
):
    session, view = window.session, window.editor.view
    old = view.sketch
    line = tmp_path / "line.csv"
    line.write_text("\n".join(f"{t},{2 * t},0" for t in np.linspace(0, 1, 20)) + "\n")
    with qtbot.waitSignal(window.failure_shown, timeout=30_000):
        assert window.open_path(str(line))
    window.last_error_box.close()
    # the old sketch comes back a turn later, as an awaited sketch does (SketchEditor.set_sketch)
    qtbot.waitUntil(lambda: len(view.sketch.boundary) == len(old.boundary), timeout=5_000)
    np.testing.assert_array_equal(view.sketch.boundary, old.boundary)  # not an empty sketch
    assert window.editor.isEnabled() and not window.editor.waiting.isVisible()
    never_done(window, monkeypatch)
    window.new_sketch()
    assert window.editor.isEnabled() and not window.editor.waiting.isVisible()
    click(qtbot, view, (0.2, 0.1))
    assert session.history.count() == 1 and len(session.state.sketch.boundary) == 1


def test_an_undo_back_to_a_loaded_leaf_of_another_document_waits_for_its_sketch(
    window, qtbot, monkeypatch
):
    session, view = window.session, window.editor.view
    nested = session.state
    session.new_document(demo("parallel"), title="parallel")  # as the Forms gallery does
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    parallel = view.sketch
    never_done(window, monkeypatch)
    window.actions["edit.undo"].trigger()
    assert session.state is nested and view.sketch is not parallel
    assert not window.editor.isEnabled()
    click(qtbot, view, parallel.boundary[0])
    assert session.state is nested and session.history.index == 0


def test_the_session_says_when_a_documents_sketch_is_not_known_yet():
    """Qt-free: a loaded leaf's document (or an undo back to one) sends sketch_waiting, a
    sketched one sends its sketch; a failed open gives back the derived sketch it had."""
    runner = Runner()
    session = Session(runner, FAST)
    got: list[object] = []
    session.sketch_shown.connect(lambda sketch, fit: got.append(sketch))
    session.sketch_waiting.connect(lambda: got.append("waiting"))
    session.open_document(demo("nested"), None, "nested")
    assert got == ["waiting"]
    runner.finish(session)
    derived = session.derived
    assert got == ["waiting", derived] and derived is not None
    line = Leaf(boundary=[[t, 2 * t, 0] for t in np.linspace(0, 1, 20)])
    session.open_document(line, None, "line.csv")
    runner.finish(session)  # fails: the nested demo comes back with its derived sketch
    assert got[-2:] == ["waiting", derived] and session.editable_sketch() is derived
    session.new_document(None, Sketch(), "new sketch")
    assert isinstance(got[-1], Sketch) and len(got[-1].boundary) == 0
    session.undo()  # back to the loaded leaf, of another document: its sketch is derived anew
    assert got[-1] == "waiting"


def test_a_click_or_key_while_a_scans_first_reconstruction_runs_leaves_it_alone(
    window, qtbot, tmp_path, monkeypatch
):
    """A scan's first reconstruction takes seconds: the whole while, the editor showed the
    previous leaf's sketch and took edits of it."""
    session, view = window.session, window.editor.view
    old = view.sketch
    # the scan is read and extracted; its reconstruction never finishes
    never_done(window, monkeypatch)
    assert window.open_path(write_points(tmp_path / "scan.txt", six_column_scan()))
    qtbot.waitUntil(lambda: session.state.scan is not None, timeout=30_000)
    opened = session.state
    click(qtbot, view, old.boundary[0])
    view.selected = (BOUNDARY, 0)  # as if a point of the old sketch were still selected
    qtbot.keyClick(view, Qt.Key.Key_Delete)
    assert session.state is opened and session.history.count() == 0
    assert not window.editor.isEnabled() and len(view.sketch.boundary) == 0
