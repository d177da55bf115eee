"""A whole vein's heights at once (issue 12), in the window: the side view dragged with the mouse
(the model and the session's side: model/test_vein_profile.py)."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPoint, Qt
from PySide6.QtGui import QColor, QPalette
from PySide6.QtTest import QTest

from leafstudio.gui.model.vein_profile import Profile

from .conftest import wait_result


def choose_vein(window, vein: int) -> None:
    window.editor.curve.setCurrentIndex(vein + 1)
    window.editor.curve.activated.emit(vein + 1)


def test_dragging_a_handle_in_the_side_view_sets_the_veins_heights_and_one_undo_restores(
    window, qtbot
):
    editor, view = window.editor, window.editor.view
    assert len(view.sketch.veins) >= 1  # the demo's sketch, derived from its result
    choose_vein(window, 0)
    side = editor.profile_view
    assert side.isVisible() and side.profile is not None and side.vein == 0
    before = view.sketch.veins[0][:, 2].copy()
    steps = window.session.history.count()
    handle = len(side.profile.t) // 2
    press = side.to_view(side.profile.t[handle], side.profile.h[handle]).toPoint()
    assert side.handle_at(press) == handle
    previews = []
    editor.preview.connect(previews.append)
    QTest.mousePress(side, Qt.MouseButton.LeftButton, pos=press)
    for dy in (-10, -20, -30):
        QTest.mouseMove(side, press + QPoint(0, dy))
    QTest.mouseRelease(side, Qt.MouseButton.LeftButton, pos=press + QPoint(0, -30))
    after = view.sketch.veins[0][:, 2]
    assert len(previews) == 3  # the 3D view followed the drag live
    assert after.max() > before.max() + 1e-6  # dragged up: the vein rose
    assert np.count_nonzero(~np.isclose(after, before, rtol=0, atol=1e-12)) >= 2  # whole vein
    assert window.session.state.sketch is view.sketch  # the session holds what the editor shows
    assert window.session.history.count() == steps + 1
    assert window.session.history.undo_text() == "Vein profile"
    wait_result(
        qtbot, window, lambda o: o.result.leaf is window.session.state.leaf
    )  # the 3D view caught up
    window.session.undo()
    np.testing.assert_array_equal(view.sketch.veins[0][:, 2], before)
    fresh = Profile.of_vein(view.sketch.vein_fractions(0), before)  # handles kept, on the heights
    np.testing.assert_allclose(side.profile.t, fresh.t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(side.profile.h, fresh.h, rtol=0, atol=1e-12)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)


def test_the_side_view_follows_a_dark_palette(window):
    dark = QPalette()
    dark.setColor(QPalette.ColorRole.Base, QColor("#17181a"))
    dark.setColor(QPalette.ColorRole.Text, QColor("#e8e8e8"))
    window.setPalette(dark)
    choose_vein(window, 0)
    image = window.editor.profile_view.grab().toImage()
    corner = image.pixelColor(2, 2)
    assert corner.lightnessF() < 0.3


def test_with_mirror_on_a_side_veins_profile_and_a_click_follow_the_bent_midrib(window, qtbot):
    from tests.gui.model.test_midrib import distance_to, lopsided_leaf

    from .test_sketch import click

    bent = lopsided_leaf(bend=0.6).mirrored(+1.0)  # symmetric about its bent midrib
    window.session.new_document(None, bent, title="bent")
    editor, view = window.editor, window.editor.view
    assert len(view.sketch.veins) == 3
    editor.mirror.setChecked(True)
    choose_vein(window, 1)  # the side vein; vein 3 is its mirror image
    side = editor.profile_view
    steps = window.session.history.count()
    press = side.to_view(side.profile.t[0], side.profile.h[0]).toPoint()
    QTest.mousePress(side, Qt.MouseButton.LeftButton, pos=press)
    QTest.mouseMove(side, press + QPoint(0, -25))
    QTest.mouseRelease(side, Qt.MouseButton.LeftButton, pos=press + QPoint(0, -25))
    veins = view.sketch.veins
    assert veins[1][0, 2] > bent.veins[1][0, 2] + 1e-6
    np.testing.assert_allclose(veins[2][:, 2], veins[1][:, 2])  # the mirror vein followed
    assert window.session.history.count() == steps + 1
    choose_vein(window, -1)  # the boundary: a click beside the bent midrib gains its mirror
    midrib = view.sketch.vein_curve(0)
    spot = np.array([0.5, 0.27])  # between two boundary points, above the midrib's lowest
    before = view.sketch.boundary
    click(qtbot, view, spot)
    added = np.array([p for p in view.sketch.boundary if not np.any(np.all(before == p, axis=1))])
    assert len(added) == 2
    offsets = view.sketch.midrib().offset(added)
    assert offsets[0] * offsets[1] < 0  # one on each side of the midrib's curve
    far = distance_to(midrib, added)
    assert np.isclose(far[0], far[1], rtol=0.02)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
