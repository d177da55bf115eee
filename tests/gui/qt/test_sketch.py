"""Sketching a leaf with simulated mouse clicks, dragging with a live 3D view, undo and redo."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPoint, Qt
from PySide6.QtGui import QKeySequence
from PySide6.QtTest import QTest

from leafstudio.gui.model.sketch_model import BOUNDARY

from .conftest import wait_result


def click(qtbot, view, xy, button=Qt.MouseButton.LeftButton, modifier=None) -> None:
    pos = view.view_point(np.asarray(xy)).toPoint()
    modifier = modifier or Qt.KeyboardModifier.NoModifier
    qtbot.mouseClick(view.viewport(), button, modifier, pos=pos)


def sketch_leaf(qtbot, window) -> None:
    """An ellipse of 10 boundary clicks and a midrib of 4 clicks."""
    window.new_sketch()
    view = window.editor.view
    for angle in np.linspace(0, 2 * np.pi, 10, endpoint=False):
        click(qtbot, view, (0.5 + 0.45 * np.cos(angle), 0.2 * np.sin(angle)))
    qtbot.mouseClick(window.editor.new_vein, Qt.MouseButton.LeftButton)
    for x in (0.15, 0.4, 0.65, 0.85):
        click(qtbot, view, (x, 0.0))


def test_sketching_with_clicks_gives_a_mesh(window, qtbot):
    sketch_leaf(qtbot, window)
    sketch = window.editor.view.sketch
    assert sketch.boundary.shape == (10, 2) and len(sketch.veins) == 1
    assert sketch.veins[0].shape == (4, 3) and np.all(sketch.veins[0][:, 2] > 0)
    outcome = wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    mesh = outcome.result.mesh
    assert mesh.n_points > 100
    assert mesh.point_data["height"].max() > 0.5 * sketch.veins[0][:, 2].max()
    xy = np.asarray(mesh.points)[:, :2]
    assert 0.03 < xy[:, 0].min() < 0.1 and 0.9 < xy[:, 0].max() < 0.97  # the clicked ellipse
    assert window.session.history.count() == 14  # 10 + 4: a vein exists from its first point


def test_undo_and_redo_every_edit(window, qtbot):
    sketch_leaf(qtbot, window)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    full = window.session.state.leaf
    assert window.actions["edit.undo"].shortcut() == QKeySequence(QKeySequence.StandardKey.Undo)
    assert window.actions["edit.redo"].shortcut() == QKeySequence(QKeySequence.StandardKey.Redo)
    window.actions["edit.undo"].trigger()
    assert window.editor.view.sketch.veins[0].shape == (3, 3)
    outcome = wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    assert outcome.result.leaf is not full
    for _ in range(3):
        window.session.history.undo()
    assert window.editor.view.sketch.boundary.shape == (10, 2)
    assert window.editor.view.sketch.veins == ()  # no empty vein is kept
    window.session.history.redo()  # the vein with its first point
    window.actions["edit.redo"].trigger()
    assert window.editor.view.sketch.veins[0].shape == (2, 3)
    while window.session.history.can_redo():
        window.session.history.redo()
    np.testing.assert_allclose(window.session.state.leaf.vein_points, full.vein_points)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)


def test_dragging_a_point_of_a_loaded_leaf_updates_live_and_undoes_to_the_original(window, qtbot):
    original = window.session.state.leaf
    view = window.editor.view
    tip = int(np.argmax(view.sketch.boundary[:, 0]))
    start = view.sketch.boundary[tip].copy()
    shown = []
    window.result_shown.connect(shown.append)
    press = view.view_point(start).toPoint()
    QTest.mousePress(view.viewport(), Qt.MouseButton.LeftButton, pos=press)
    for step in range(1, 6):
        QTest.mouseMove(view.viewport(), press + QPoint(12 * step, 0))
        qtbot.waitUntil(lambda: window.worker.is_idle(), timeout=60_000)
    QTest.mouseRelease(view.viewport(), Qt.MouseButton.LeftButton, pos=press + QPoint(60, 0))
    outcome = wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    assert len(shown) >= 3  # the 3D view followed the drag
    assert (
        window.session.history.count() == 1 and window.session.history.undo_text() == "Move point"
    )
    moved = view.sketch.boundary[tip]
    assert moved[0] > start[0] + 1e-3
    length = np.ptp(np.asarray(outcome.result.mesh.points)[:, 0])  # the tip moved outward
    assert length > np.ptp(original.boundary[:, 0]) + 1e-3
    window.session.history.undo()
    assert window.session.state.leaf is original
    wait_result(qtbot, window, lambda o: o.result.leaf is original)


def test_right_click_deletes_and_height_spin_box_sets_a_vein_height(window, qtbot):
    view = window.editor.view
    n = len(view.sketch.boundary)
    click(qtbot, view, view.sketch.boundary[3], Qt.MouseButton.RightButton)
    assert len(view.sketch.boundary) == n - 1
    click(qtbot, view, view.sketch.veins[0][2, :2], modifier=Qt.KeyboardModifier.ControlModifier)
    assert view.selected == (0, 2) and window.editor.height.isEnabled()
    window.editor.height.setValue(0.08)
    assert view.sketch.veins[0][2, 2] == 0.08
    assert window.session.history.count() == 2
    assert view.selected[0] != BOUNDARY


def test_an_undo_during_a_point_drag_drops_the_drag(window, qtbot):
    """Review s3 finding 3, for a point of the sketch: Ctrl+Z while a point is dragged ends the
    drag with no step (it went on from the sketch before the undo, and its step from the state
    before it); the next drag's step starts from the state the undo made."""
    session, history, view = window.session, window.session.history, window.editor.view
    session.set_params(session.params.with_(k=5))  # "Change K": 3 -> 5
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    tip = int(np.argmax(view.sketch.boundary[:, 0]))
    press = view.view_point(view.sketch.boundary[tip]).toPoint()
    QTest.mousePress(view.viewport(), Qt.MouseButton.LeftButton, pos=press)
    QTest.mouseMove(view.viewport(), press + QPoint(12, 0))
    assert session.state.sketch is view.sketch  # the drag's preview
    window.actions["edit.undo"].trigger()
    undone = session.state
    assert undone.params.k == 3 and view._drag is None
    QTest.mouseMove(view.viewport(), press + QPoint(24, 0))
    QTest.mouseRelease(view.viewport(), Qt.MouseButton.LeftButton, pos=press + QPoint(24, 0))
    assert history.index == 0 and session.state is undone  # no step, nothing moved
    QTest.mousePress(view.viewport(), Qt.MouseButton.LeftButton, pos=press)
    QTest.mouseMove(view.viewport(), press + QPoint(12, 0))
    QTest.mouseRelease(view.viewport(), Qt.MouseButton.LeftButton, pos=press + QPoint(12, 0))
    assert history.index == 1 and history.undo_text() == "Move point"
    window.actions["edit.undo"].trigger()
    assert session.state is undone  # was K 5: the undone change came back
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)


def test_an_undo_that_removes_the_dragged_point_ends_the_drag_without_an_error(window, qtbot):
    """The last midrib point dragged, Ctrl+Z removes it: the drag went on moving a point the
    sketch no longer has (an IndexError in the view's mouse move)."""
    sketch_leaf(qtbot, window)
    view, history = window.editor.view, window.session.history
    press = view.view_point(view.sketch.veins[0][-1, :2]).toPoint()
    QTest.mousePress(view.viewport(), Qt.MouseButton.LeftButton, pos=press)
    QTest.mouseMove(view.viewport(), press + QPoint(0, 10))
    window.actions["edit.undo"].trigger()  # the point's "Add point" undone
    undone, steps = window.session.state, history.index
    assert view.sketch.veins[0].shape == (3, 3) and view.sketch is undone.sketch
    QTest.mouseMove(view.viewport(), press + QPoint(0, 20))
    QTest.mouseRelease(view.viewport(), Qt.MouseButton.LeftButton, pos=press + QPoint(0, 20))
    assert window.session.state is undone and history.index == steps
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)


def test_the_sketch_view_draws_a_scans_holes(qtbot):
    """A scan's real hole (Sketch.hole_curves) is drawn on the flat blade, filled with the
    view's background: the mesh leaves it open."""
    from types import SimpleNamespace

    from PySide6.QtWidgets import QGraphicsPathItem

    from leafstudio.gui.model.sketch_model import Sketch
    from leafstudio.gui.qt.sketch_view import SketchView

    t = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    ring = np.column_stack([0.3 + 0.1 * np.cos(t), 0.1 * np.sin(t), np.zeros_like(t)])
    bend = SimpleNamespace(flat_holes=lambda: [ring])
    outline = np.column_stack([np.cos(t), 0.5 * np.sin(t)])
    view = SketchView()
    qtbot.addWidget(view)
    view.set_sketch(Sketch(boundary=outline, bend=bend), fit=True)
    paths = [i for i in view.scene().items() if isinstance(i, QGraphicsPathItem)]
    rects = [i.path().boundingRect() for i in paths]
    assert any(abs(r.center().x() - 0.3) < 1e-6 and abs(r.width() - 0.2) < 1e-3 for r in rects)


def test_a_curve_is_drawn_as_the_path_of_a_line_to_each_point(qapp):
    """SketchView._path builds its path from bytes made by numpy (a lineTo per point cost
    12 ms of a 2M-point scan's sketch, issue 24): the same path, open or closed."""
    from PySide6.QtCore import QPointF
    from PySide6.QtGui import QPainterPath

    from leafstudio.gui.qt.sketch_view import SketchView

    t = np.linspace(0, 2 * np.pi, 300, endpoint=False)
    points = np.column_stack([np.cos(t), 0.4 * np.sin(3 * t), t])  # a vein's third column too
    for closed in (False, True):
        expected = QPainterPath(QPointF(points[0, 0], -points[0, 1]))
        for x, y in points[1:, :2]:
            expected.lineTo(x, -y)
        if closed:
            expected.closeSubpath()
        assert SketchView._path(points, closed) == expected
