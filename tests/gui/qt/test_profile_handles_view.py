"""The vein side view as a designer uses it (issue 12, Xvfb): a drag starts from the vein's own
heights, handles are added by a double-click and removed by Delete, a right-click or a
double-click, the keyboard chooses and nudges them, and each change of heights is one undo step."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import QEvent, QPoint, QPointF, Qt
from PySide6.QtGui import QColor, QKeyEvent, QMouseEvent
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QApplication, QLineEdit, QVBoxLayout, QWidget

from leafstudio.gui.qt.profile_paint import HANDLE_PIXELS, SELECTED
from leafstudio.gui.qt.profile_view import BIG_NUDGE, NUDGE, ProfileView
from tests.gui.model.test_profile_handles import curled, wiggly_vein

from .conftest import wait_result


@pytest.fixture
def side(qtbot):
    """The side view on an 11-point vein between two text fields, wired like the editor: a
    released edit is shown back to it; `side.steps` lists the (before, after) undo steps."""
    holder = QWidget()
    layout = QVBoxLayout(holder)
    view = ProfileView()
    layout.addWidget(QLineEdit())
    layout.addWidget(view)
    layout.addWidget(QLineEdit())
    qtbot.addWidget(holder)
    holder.resize(420, 260)
    holder.show()
    qtbot.waitExposed(holder)
    holder.activateWindow()  # keys and focus need the active window
    qtbot.waitUntil(holder.isActiveWindow)
    view.set_vein(wiggly_vein(11), 0)
    view.steps = []
    view.released.connect(lambda before, after: view.steps.append((before, after)))
    view.released.connect(lambda before, after: view.set_vein(after, 0))
    yield view  # the holder lives as long as the test
    holder.close()


def heights(view: ProfileView) -> np.ndarray:
    return view.sketch.veins[0][:, 2].copy()


def spot(view: ProfileView, index: int) -> QPoint:
    return view.to_view(view.profile.t[index], view.profile.h[index]).toPoint()


def height_per_pixel(view: ProfileView) -> float:
    lo, hi = view._heights_range()
    return (hi - lo) / view._plot().height()


def test_a_one_pixel_drag_on_a_long_vein_moves_no_height_by_more_than_a_pixel(side):
    """The finding: the first drag on a vein of more than 5 points smoothed every height between
    the handles (here up to ~0.03, some 20 pixels, for a 1-pixel drag)."""
    before, pixel = heights(side), height_per_pixel(side)
    press = spot(side, 2)
    QTest.mousePress(side, Qt.MouseButton.LeftButton, pos=press)
    QTest.mouseRelease(side, Qt.MouseButton.LeftButton, pos=press)
    assert side.steps == [] and np.array_equal(heights(side), before)  # a click changes nothing
    QTest.mousePress(side, Qt.MouseButton.LeftButton, pos=press + QPoint(3, 2))  # off-centre
    QTest.mouseMove(side, press + QPoint(3, 1))
    QTest.mouseRelease(side, Qt.MouseButton.LeftButton, pos=press + QPoint(3, 1))
    change = heights(side) - before
    assert len(side.steps) == 1
    assert 0 < np.abs(change).max() <= 1.01 * pixel
    shares, t = side.sketch.vein_fractions(0), side.profile.t
    outside = (shares <= t[1]) | (shares >= t[3])
    assert np.all(change[outside] == 0)  # beyond the neighbouring handles: untouched


def test_double_clicking_the_line_adds_a_handle_that_changes_no_height(side):
    before, count = heights(side), len(side.profile.t)
    t = float(np.mean(side.profile.t[1:3]))
    on_line = side.to_view(t, float(side.profile.heights(np.array([t]))[0])).toPoint()
    QTest.mouseDClick(side, Qt.MouseButton.LeftButton, pos=on_line + QPoint(0, 3))
    assert len(side.profile.t) == count + 1 and side.selected == 2
    assert abs(side.profile.t[2] - t) < 2 * height_per_pixel(side) + 0.01
    np.testing.assert_array_equal(heights(side), before)
    assert side.steps == []
    QTest.mouseDClick(side, Qt.MouseButton.LeftButton, pos=on_line + QPoint(0, 40))  # off the line
    assert len(side.profile.t) == count + 1
    # the new handle bends the vein between its neighbours only
    QTest.mousePress(side, Qt.MouseButton.LeftButton, pos=spot(side, 2))
    QTest.mouseMove(side, spot(side, 2) + QPoint(0, -30))
    QTest.mouseRelease(side, Qt.MouseButton.LeftButton, pos=spot(side, 2))
    shares, ts = side.sketch.vein_fractions(0), side.profile.t
    outside = (shares <= ts[1]) | (shares >= ts[3])
    moved = heights(side) != before
    assert moved.any() and not moved[outside].any() and len(side.steps) == 1


def test_a_handle_is_removed_by_delete_right_click_or_double_click_but_not_the_ends(side, qtbot):
    QTest.mousePress(side, Qt.MouseButton.LeftButton, pos=spot(side, 2))
    QTest.mouseMove(side, spot(side, 2) + QPoint(0, -40))
    QTest.mouseRelease(side, Qt.MouseButton.LeftButton, pos=spot(side, 2) + QPoint(0, -40))
    assert side.hasFocus() and side.selected == 2 and len(side.steps) == 1
    raised, t2 = heights(side), side.profile.t[2]
    QTest.keyClick(side, Qt.Key.Key_Delete)
    assert len(side.profile.t) == 4 and t2 not in side.profile.t and len(side.steps) == 2
    before, after = side.steps[-1]
    np.testing.assert_array_equal(before.veins[0][:, 2], raised)
    assert after is side.sketch
    under = int(np.argmin(np.abs(side.sketch.vein_fractions(0) - t2)))
    assert heights(side)[under] < raised[under] - 10 * height_per_pixel(side)  # the bump is gone
    QTest.mouseClick(side, Qt.MouseButton.RightButton, pos=spot(side, 1))
    assert len(side.profile.t) == 3
    QTest.mouseDClick(side, Qt.MouseButton.LeftButton, pos=spot(side, 1))
    assert len(side.profile.t) == 2
    for index in (0, 1):  # the ends stay
        side.select(index)
        QTest.keyClick(side, Qt.Key.Key_Backspace)
        QTest.mouseClick(side, Qt.MouseButton.RightButton, pos=spot(side, index))
        QTest.mouseDClick(side, Qt.MouseButton.LeftButton, pos=spot(side, index))
    assert list(side.profile.t) == [0.0, 1.0]


def test_keys_choose_handles_and_nudge_with_one_undo_step_per_press_or_held_run(side):
    QTest.mouseClick(side, Qt.MouseButton.LeftButton, pos=side._plot().center().toPoint())
    assert side.hasFocus() and side.selected is None
    QTest.keyClick(side, Qt.Key.Key_Right)
    assert side.selected == 0
    QTest.keyClick(side, Qt.Key.Key_Right)
    QTest.keyClick(side, Qt.Key.Key_Right)
    QTest.keyClick(side, Qt.Key.Key_Left)
    assert side.selected == 1
    step = NUDGE * side.sketch.extent()
    under = int(np.argmin(np.abs(side.sketch.vein_fractions(0) - side.profile.t[1])))
    h0 = heights(side)[under]
    QTest.keyClick(side, Qt.Key.Key_Up)
    QTest.keyClick(side, Qt.Key.Key_Up)
    assert len(side.steps) == 2  # a press is a step
    assert np.isclose(heights(side)[under], h0 + 2 * step)
    QTest.keyClick(side, Qt.Key.Key_Down, Qt.KeyboardModifier.ShiftModifier)
    assert np.isclose(heights(side)[under], h0 + 2 * step - BIG_NUDGE * side.sketch.extent())
    assert len(side.steps) == 3
    # a held key: presses repeat, one step when it is let go
    app, h1 = QApplication.instance(), heights(side)[under]
    app.sendEvent(
        side, QKeyEvent(QEvent.Type.KeyPress, Qt.Key.Key_Up, Qt.KeyboardModifier.NoModifier)
    )
    for _ in range(4):
        for kind in (QEvent.Type.KeyRelease, QEvent.Type.KeyPress):
            event = QKeyEvent(kind, Qt.Key.Key_Up, Qt.KeyboardModifier.NoModifier, "", True)
            app.sendEvent(side, event)
    assert len(side.steps) == 3 and np.isclose(heights(side)[under], h1 + 5 * step)
    app.sendEvent(
        side, QKeyEvent(QEvent.Type.KeyRelease, Qt.Key.Key_Up, Qt.KeyboardModifier.NoModifier)
    )
    assert len(side.steps) == 4
    np.testing.assert_array_equal(side.steps[-1][0].veins[0][:, 2][under], h1)


def test_tab_goes_through_the_handles_then_on(side):
    first = side.parentWidget().findChildren(QLineEdit)[0]
    first.setFocus()
    QTest.keyClick(first, Qt.Key.Key_Tab)
    assert side.hasFocus() and side.selected == 0
    for expected in range(1, len(side.profile.t)):
        QTest.keyClick(side, Qt.Key.Key_Tab)
        assert side.hasFocus() and side.selected == expected
    QTest.keyClick(side, Qt.Key.Key_Tab)  # past the last handle: the next field
    assert not side.hasFocus()
    QTest.keyClick(
        side.parentWidget().focusWidget(), Qt.Key.Key_Tab, Qt.KeyboardModifier.ShiftModifier
    )
    assert side.hasFocus() and side.selected == len(side.profile.t) - 1
    QTest.keyClick(side, Qt.Key.Key_Backtab)
    assert side.selected == len(side.profile.t) - 2
    side.select(None)  # a click beside the handles chose none: Tab starts from the first
    QTest.keyClick(side, Qt.Key.Key_Tab)
    assert side.hasFocus() and side.selected == 0


def test_the_selected_handle_is_drawn_filled_with_a_focus_ring(side):
    side.setFocus()
    side.select(3)
    palette = side.palette()
    highlight = palette.color(palette.ColorRole.Highlight)
    ring = HANDLE_PIXELS / 2 + 1.5 + 3.0  # the selected handle's half side, and the ring's gap

    def colours(widget: ProfileView, index: int, above: float) -> list[QColor]:
        """Colours at distances around `above` logical pixels over handle `index`'s centre,
        read in device pixels."""
        image = widget.grab().toImage()
        ratio = image.devicePixelRatio()
        centre = side.to_view(side.profile.t[index], side.profile.h[index])
        return [
            image.pixelColor(round(centre.x() * ratio), round((centre.y() - d) * ratio))
            for d in np.arange(above - 1.5, above + 1.51, 0.5)
        ]

    def near(a: QColor, b: QColor) -> bool:
        return (
            max(abs(a.red() - b.red()), abs(a.green() - b.green()), abs(a.blue() - b.blue())) < 40
        )

    assert colours(side, 3, 0.0)[3] == QColor(SELECTED)
    assert colours(side, 2, 0.0)[3] == palette.color(palette.ColorRole.Base)
    assert any(near(c, highlight) for c in colours(side, 3, ring))
    assert not any(near(c, highlight) for c in colours(side, 2, ring))  # only the selected one
    side.clearFocus()
    assert not any(near(c, highlight) for c in colours(side, 3, ring))  # no focus, no ring


def test_the_cursor_tells_a_handle_from_the_line_from_empty_space(side):
    t = float(np.mean(side.profile.t[1:3]))
    on_line = side.to_view(t, float(side.profile.heights(np.array([t]))[0])).toPoint()
    for pos, shape in (
        (spot(side, 1), Qt.CursorShape.SizeAllCursor),
        (on_line, Qt.CursorShape.CrossCursor),
        (on_line + QPoint(0, 40), Qt.CursorShape.ArrowCursor),
    ):
        move = QMouseEvent(
            QEvent.Type.MouseMove,
            QPointF(pos),
            side.mapToGlobal(QPointF(pos)),
            Qt.MouseButton.NoButton,
            Qt.MouseButton.NoButton,
            Qt.KeyboardModifier.NoModifier,
        )
        QApplication.sendEvent(side, move)  # QTest.mouseMove may leave a hover move out
        assert side.cursor().shape() == shape


def test_drawing_works_out_the_veins_curve_a_few_times_not_once_per_drawn_point(side, monkeypatch):
    """Each drawn point asked for the plot's height range, which made the vein's spline anew:
    ~75 ms of CPU per repaint of an 11-point vein, on every move of a drag."""
    from leafstudio.gui.model.sketch_model import Sketch

    calls = []
    made = Sketch.vein_curve
    monkeypatch.setattr(Sketch, "vein_curve", lambda self, i: calls.append(i) or made(self, i))
    side.grab()
    assert 0 < len(calls) <= 3
    QTest.mousePress(side, Qt.MouseButton.LeftButton, pos=spot(side, 2))
    calls.clear()
    QTest.mouseMove(side, spot(side, 2) + QPoint(0, -5))
    side.grab()
    assert 0 < len(calls) <= 3
    QTest.mouseRelease(side, Qt.MouseButton.LeftButton, pos=spot(side, 2))


def test_the_boundary_shows_its_heights_read_only(side):
    from leafstudio.gui.model.sketch_model import BOUNDARY, Sketch

    sketch = curled(wiggly_vein(5))
    side.set_vein(sketch, BOUNDARY)
    assert side.has_boundary() and side.profile is None and not side.has_vein()
    shares, heights, _ = side._outline
    lo, hi = side._heights_range()
    assert lo < heights.min() and hi > heights.max()  # the whole margin fits the view
    image = side.grab().toImage()
    ratio = image.devicePixelRatio()
    base = side.palette().color(side.palette().ColorRole.Base)
    for i in np.linspace(0, len(shares) - 1, 7).astype(int)[1:-1]:  # the curve is drawn
        where = side.to_view(shares[i], heights[i])
        assert image.pixelColor(round(where.x() * ratio), round(where.y() * ratio)) != base
    side.setFocus()
    QTest.keyClick(side, Qt.Key.Key_Right)
    QTest.keyClick(side, Qt.Key.Key_Up)
    middle = side.to_view(shares[len(shares) // 2], heights[len(shares) // 2]).toPoint()
    QTest.mouseDClick(side, Qt.MouseButton.LeftButton, pos=middle)
    assert side.steps == [] and side.sketch is sketch and side.profile is None  # read only
    side.set_vein(Sketch(boundary=sketch.boundary[:2]), BOUNDARY)  # no boundary yet
    assert not side.has_boundary()
    side.grab()


def test_in_the_window_a_drag_a_nudge_and_a_removal_are_undo_steps_that_bring_back_handles(
    window, qtbot
):
    """On the nested demo's midrib (8 points, derived from its result): a 1-pixel drag moves no
    height by more than a pixel (the finding, as seen in the app); a key press and a removal
    are one "Vein profile" step each; undo brings back the heights and the removed handle."""
    editor = window.editor
    editor.curve.setCurrentIndex(1)
    editor.curve.activated.emit(1)
    side, view = editor.profile_view, editor.view
    assert len(view.sketch.veins[0]) > 5
    window.activateWindow()
    qtbot.waitUntil(window.isActiveWindow)
    original, pixel = view.sketch.veins[0][:, 2].copy(), height_per_pixel(side)
    steps = window.session.history.count()
    QTest.mousePress(side, Qt.MouseButton.LeftButton, pos=spot(side, 2))
    QTest.mouseMove(side, spot(side, 2) + QPoint(0, -1))
    QTest.mouseRelease(side, Qt.MouseButton.LeftButton, pos=spot(side, 2) + QPoint(0, -1))
    assert window.session.history.count() == steps + 1
    assert 0 < np.abs(view.sketch.veins[0][:, 2] - original).max() <= 1.01 * pixel
    assert side.hasFocus() and side.selected == 2
    QTest.keyClick(side, Qt.Key.Key_Up)
    assert window.session.history.count() == steps + 2
    assert window.session.history.undo_text() == "Vein profile"
    assert window.session.state.sketch is view.sketch  # the session holds what the editor shows
    assert side.selected == 2  # still chosen: the next press goes on from it
    nudged, handles = view.sketch.veins[0][:, 2].copy(), side.profile.t.copy()
    QTest.keyClick(side, Qt.Key.Key_Delete)
    assert window.session.history.count() == steps + 3 and len(side.profile.t) == len(handles) - 1
    assert not np.array_equal(view.sketch.veins[0][:, 2], nudged)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    window.session.undo()
    np.testing.assert_array_equal(view.sketch.veins[0][:, 2], nudged)
    np.testing.assert_array_equal(side.profile.t, handles)  # the removed handle is back
    window.session.redo()
    assert len(side.profile.t) == len(handles) - 1
    for _ in range(3):
        window.session.undo()
    np.testing.assert_array_equal(view.sketch.veins[0][:, 2], original)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)


# --- review s3 finding 3: an undo or redo during an edit of the side view -------------------------
def press_key(widget: QWidget, kind: QEvent.Type, key: Qt.Key, repeat: bool = False) -> None:
    event = QKeyEvent(kind, key, Qt.KeyboardModifier.NoModifier, "", repeat)
    QApplication.instance().sendEvent(widget, event)


def on_the_midrib(window, qtbot) -> ProfileView:
    """K made 5 (one "Change K" step), the midrib chosen, handle 2 selected, keys to the view."""
    window.session.set_params(window.session.params.with_(k=5))
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    window.editor.curve.setCurrentIndex(1)
    window.editor.curve.activated.emit(1)
    window.activateWindow()
    qtbot.waitUntil(window.isActiveWindow)
    side = window.editor.profile_view
    side.setFocus()
    side.select(2)
    return side


def test_an_undo_while_up_is_held_ends_the_run_and_the_next_step_starts_after_it(window, qtbot):
    """Ctrl+Z while Up was held: the run went on from before the undo, so the next nudge's
    step went from K=5 to K=3 and undoing it brought back the change the user had undone."""
    session, history = window.session, window.session.history
    side = on_the_midrib(window, qtbot)
    press_key(side, QEvent.Type.KeyPress, Qt.Key.Key_Up)  # held: the run's first preview
    assert history.count() == 1 and window.editor.view.sketch is session.state.sketch
    window.actions["edit.undo"].trigger()
    undone = session.state
    assert undone.params.k == 3 and undone.sketch is None  # the loaded leaf, as opened
    press_key(side, QEvent.Type.KeyPress, Qt.Key.Key_Up, repeat=True)  # the key repeats
    press_key(side, QEvent.Type.KeyRelease, Qt.Key.Key_Up)
    # the run ended at the undo: its repeats and its release change nothing
    assert history.index == 0 and session.state is undone
    press_key(side, QEvent.Type.KeyPress, Qt.Key.Key_Down)  # an ordinary nudge later
    press_key(side, QEvent.Type.KeyRelease, Qt.Key.Key_Down)
    assert history.index == 1 and history.steps[0].before is undone
    window.actions["edit.undo"].trigger()
    assert session.state is undone and session.params.k == 3  # was K 5: the undone change
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)


@pytest.mark.parametrize("move", ["undo", "redo"])
def test_an_undo_or_redo_during_a_handle_drag_drops_the_drag(window, qtbot, move):
    """A handle dragged when Ctrl+Z (or Ctrl+Y) comes: the drag ends there with no step, and
    letting go after it changes nothing; the next drag's step starts from the undone state."""
    session, history = window.session, window.session.history
    side = on_the_midrib(window, qtbot)
    if move == "redo":
        window.actions["edit.undo"].trigger()  # K 3, "Change K" to redo
    count, start = history.count(), spot(side, 2)
    QTest.mousePress(side, Qt.MouseButton.LeftButton, pos=start)
    QTest.mouseMove(side, start + QPoint(0, -6))
    assert session.state.sketch is not None  # the drag's preview
    (window.actions["edit.undo"] if move == "undo" else window.actions["edit.redo"]).trigger()
    moved_to = session.state
    assert side.grabbed is None and moved_to.params.k == (3 if move == "undo" else 5)
    QTest.mouseMove(side, start + QPoint(0, -12))
    QTest.mouseRelease(side, Qt.MouseButton.LeftButton, pos=start + QPoint(0, -12))
    assert history.count() == count and session.state is moved_to  # no step, nothing moved
    start = spot(side, 2)
    QTest.mousePress(side, Qt.MouseButton.LeftButton, pos=start)
    QTest.mouseMove(side, start + QPoint(0, -6))
    QTest.mouseRelease(side, Qt.MouseButton.LeftButton, pos=start + QPoint(0, -6))
    assert history.steps[history.index - 1].before is moved_to
    window.actions["edit.undo"].trigger()
    assert session.state is moved_to
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)


@pytest.mark.parametrize("how", ["keys", "drag"])
def test_a_new_document_during_an_edit_of_the_side_view_ends_it(window, qtbot, how):
    """A demo opened while Up was held (or a handle dragged): letting go committed the old
    document's edited sketch as a "Vein profile" step of the new one, replacing its leaf."""
    session, history = window.session, window.session.history
    side = on_the_midrib(window, qtbot)
    start = spot(side, 2)
    if how == "keys":
        press_key(side, QEvent.Type.KeyPress, Qt.Key.Key_Up)
    else:
        QTest.mousePress(side, Qt.MouseButton.LeftButton, pos=start)
        QTest.mouseMove(side, start + QPoint(0, -6))
    window.open_demo("parallel")
    opened = session.state
    if how == "keys":
        press_key(side, QEvent.Type.KeyPress, Qt.Key.Key_Up, repeat=True)
        press_key(side, QEvent.Type.KeyRelease, Qt.Key.Key_Up)
    else:
        QTest.mouseMove(side, start + QPoint(0, -12))
        QTest.mouseRelease(side, Qt.MouseButton.LeftButton, pos=start + QPoint(0, -12))
    assert session.state is opened and history.count() == 0
    wait_result(qtbot, window, lambda o: o.result.leaf is opened.leaf)
