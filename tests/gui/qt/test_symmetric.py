"""Mirror editing in the window (issue 12 leftovers): the checkbox, Save and Open, and the sketch
editor saying why an edit was not mirrored (the session's side: model/test_symmetric.py)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.gui.model.test_symmetric import bent_leaf

from .conftest import wait_result
from .test_sketch import sketch_leaf


def test_in_the_window_mirror_is_saved_reopened_and_undone(window, qtbot, tmp_path):
    """Before: Mirror was a switch of the editor alone; a project drawn with it came back off."""
    sketch_leaf(qtbot, window)
    editor = window.editor
    editor.mirror.setChecked(True)
    assert window.session.state.sketch.symmetric and window.session.is_modified()
    assert window.session.history.undo_text() == "Mirror on"
    path = tmp_path / "drawn.leaf.json"
    assert window.save_to(str(path))
    editor.mirror.setChecked(False)  # a later change, not saved
    assert window.session.is_modified() and not window.session.state.sketch.symmetric
    window.session.undo()
    assert (
        editor.mirror.isChecked() and not window.session.is_modified()
    )  # the checkbox follows undo
    editor.mirror.setChecked(False)
    assert window.open_path(str(path))
    qtbot.waitUntil(lambda: window.session.state.path == str(path), timeout=30_000)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    assert editor.mirror.isChecked() and editor.view.mirror
    assert window.session.state.sketch.symmetric and not window.session.is_modified()
    window.new_sketch()  # a new drawing starts with Mirror off
    assert not editor.mirror.isChecked()


def test_the_sketch_editor_says_why_an_edit_was_not_mirrored(qtbot):
    """In the dock, not in a dialog: a drag passes through many such edits."""
    from leafstudio.gui.qt.sketch import SketchEditor

    from .test_sketch import click

    editor = SketchEditor()
    qtbot.addWidget(editor)
    editor.resize(500, 600)
    editor.show()
    sketch = bent_leaf(radius=1.0, outside=1.3, inside=0.3)
    editor.set_sketch(sketch, fit=True)
    assert editor.mirror.isChecked() and editor.mirror_note.isHidden()
    edits = []
    editor.committed.connect(lambda before, after, text: edits.append(after))
    before = editor.view.transform()
    click(qtbot, editor.view, (1.9, 0.5))  # beside the outer half: a new boundary point
    assert editor.view.transform() == before  # the note shows over the view: no jump
    assert len(edits) == 1 and len(edits[0].boundary) == len(sketch.boundary) + 1  # not mirrored
    assert editor.mirror_note.isVisible() and "Not mirrored" in editor.mirror_note.text()
    inside = editor.view.viewport().geometry()
    assert inside.contains(editor.mirror_note.geometry())  # over the drawing, clear of scroll bars
    editor.resize(360, 600)
    qtbot.waitUntil(lambda: editor.view.viewport().width() < inside.width())
    assert editor.view.viewport().geometry().contains(editor.mirror_note.geometry())
    click(qtbot, editor.view, (0.75, 0.41))  # inside the inner half: this one fits
    offsets = edits[1].midrib().offset(edits[1].boundary)
    assert -offsets.min() == pytest.approx(offsets.max(), rel=1e-6)  # mirrored: symmetric
    assert editor.mirror_note.isHidden()
    editor.mirror.setChecked(False)
    assert not editor.view.mirror and editor.mirror_note.isHidden()


def test_a_drag_past_the_bend_pauses_the_mirror_and_says_so_without_a_dialog(qtbot):
    from PySide6.QtCore import Qt
    from PySide6.QtWidgets import QMessageBox

    from leafstudio.gui.qt.sketch import SketchEditor

    editor = SketchEditor()
    qtbot.addWidget(editor)
    editor.resize(500, 600)
    editor.show()
    editor.set_sketch(bent_leaf(radius=1.0, outside=0.3, inside=0.3), fit=True)
    view = editor.view
    index = 8  # the outside's widest control point
    start = view.sketch.boundary[index]
    direction = start / np.linalg.norm(start)  # outward from the bend's centre
    previews = []
    view.preview.connect(previews.append)
    qtbot.mousePress(
        view.viewport(), Qt.MouseButton.LeftButton, pos=view.view_point(start).toPoint()
    )
    inner = []
    for radius in (1.5, 2.2, 1.5):  # 0.5 out (mirrors), 1.2 out (would fold), back again
        qtbot.mouseMove(view.viewport(), view.view_point(radius * direction).toPoint())
        offsets = view.sketch.midrib().offset(view.sketch.boundary)
        inner.append(offsets.max())  # how far the inside reaches
        assert editor.mirror_note.isVisible() == (radius > 2.0)
    qtbot.mouseRelease(
        view.viewport(), Qt.MouseButton.LeftButton, pos=view.view_point(1.5 * direction).toPoint()
    )
    assert inner[0] == pytest.approx(0.5, abs=0.02)  # mirrored
    assert inner[1] == pytest.approx(inner[0])  # not mirrored past the bend's centre
    assert inner[2] == pytest.approx(0.5, abs=0.02) and len(previews) == 3
    assert not editor.findChildren(QMessageBox)
