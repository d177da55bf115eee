"""The window as a drawing tool (issue 12's findings, where only the window can show them): the
sketch view holds still, the camera frames each leaf, vein branches, crossings in red, one
orientation, undo of parameters with Ctrl+Y, in-place updates, high-DPI sizes and dark themes."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPoint, Qt
from PySide6.QtGui import QColor, QKeySequence, QPalette
from PySide6.QtTest import QTest

from leafstudio.gui.model.layers import vein_color
from leafstudio.gui.qt.main_window import MainWindow
from tests.leaves import sketch_clicks as ellipse_clicks

from .conftest import wait_result
from .test_sketch import click


def leaf_fill(window: MainWindow) -> tuple[float, float]:
    """Share of the 3D view's width and height the mesh's points span on screen."""
    xy = window.viewport.display_points(np.asarray(window.session.result.triangle_mesh.points)[::7])
    w, h = window.viewport.plotter.renderer.GetSize()
    return np.ptp(xy[:, 0]) / w, np.ptp(xy[:, 1]) / h


def camera(window: MainWindow) -> np.ndarray:
    cam = window.viewport.plotter.camera
    return np.array([*cam.position, *cam.focal_point, *cam.up])


def test_the_sketch_view_holds_still_while_drawing_and_fit_shows_the_whole_leaf(window, qtbot):
    window.new_sketch()
    view = window.editor.view
    before = view.transform()
    for xy in ellipse_clicks()[[0, 4, 8]]:
        click(qtbot, view, xy)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    for xy in ellipse_clicks()[[2, 6, 10]]:
        click(qtbot, view, xy)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    assert view.transform() == before  # no jump onto the first three points
    view.scale(3, 3)
    view.fit()
    rect = view.mapToScene(view.viewport().rect()).boundingRect()
    curve = view.sketch.boundary_curve()
    assert rect.left() < curve[:, 0].min() and rect.right() > curve[:, 0].max()
    assert rect.top() < -curve[:, 1].max() and rect.bottom() > -curve[:, 1].min()


def test_each_demo_is_framed_and_a_parameter_change_keeps_the_camera(window, qtbot):
    wide, high = leaf_fill(window)
    assert max(wide, high) >= 0.6 and min(wide, high) >= 0.35, (wide, high)  # nested, in iso
    window.open_demo("parallel")
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    wide, high = leaf_fill(window)
    assert max(wide, high) >= 0.6 and min(wide, high) >= 0.35, (wide, high)
    window.viewport.plotter.camera.azimuth = 25.0  # the user turns the view
    turned = camera(window)
    window.panel.k.setValue(window.panel.k.value() + 1)
    wait_result(qtbot, window, lambda o: o.result.params.k == window.panel.k.value())
    np.testing.assert_allclose(camera(window), turned)


def test_the_top_view_shows_the_leaf_the_way_round_the_sketch_does(window, qtbot):
    window.viewport.camera("top")
    frame = window.session.view_frame()
    sketch = window.editor.view.sketch
    tip = sketch.boundary[np.argmax(sketch.boundary[:, 0])]  # right-most in the sketch
    side = sketch.boundary[np.argmax(sketch.boundary[:, 1])]  # top-most in the sketch

    def screen(xy):
        return window.viewport.display_points(frame.to_world(np.asarray([xy]), np.zeros(1)))[0]

    centre = screen(sketch.boundary.mean(axis=0))
    assert screen(tip)[0] > centre[0] + 10  # right in the sketch: right on screen
    assert screen(side)[1] > centre[1] + 5  # up in the sketch: up on screen (display y is up)


def test_a_new_vein_started_on_the_midrib_branches_and_never_selects(window, qtbot):
    view = window.editor.view
    midrib = view.sketch.veins[0].copy()
    count = len(view.sketch.veins)
    for _ in range(2):  # two side veins from the same midrib point
        qtbot.mouseClick(window.editor.new_vein, Qt.MouseButton.LeftButton)
        click(qtbot, view, midrib[3, :2])
        click(qtbot, view, midrib[3, :2] + np.array([0.1, 0.15]))
    veins = view.sketch.veins
    assert len(veins) == count + 2
    np.testing.assert_array_equal(veins[0], midrib)  # the midrib is untouched
    for vein in veins[-2:]:
        assert len(vein) == 2
        assert np.linalg.norm(vein[0, :2] - midrib[3, :2]) < 0.02  # starts on the midrib
    assert view.active == count + 1 and window.session.history.undo_text() == "Add point"


def test_a_drag_that_crosses_the_boundary_is_red_and_keeps_the_last_mesh(window, qtbot):
    view = window.editor.view
    boundary = view.sketch.boundary
    shown = window.session.result
    mesh = window.viewport.plotter.actors["mesh"]
    points = np.asarray(mesh.mapper.dataset.points).copy()
    top = int(np.argmax(boundary[:, 1]))
    press = view.view_point(boundary[top]).toPoint()
    target = view.view_point(boundary[top] * [1.0, -1.0] + [0.0, -0.1]).toPoint()
    QTest.mousePress(view.viewport(), Qt.MouseButton.LeftButton, pos=press)
    QTest.mouseMove(view.viewport(), target)
    qtbot.waitUntil(lambda: len(view.crossings) > 0, timeout=10_000)
    assert "crosses itself" in window.status_text.text()
    assert window.session.result is shown
    np.testing.assert_array_equal(np.asarray(mesh.mapper.dataset.points), points)
    QTest.mouseMove(view.viewport(), press + QPoint(2, 0))
    QTest.mouseRelease(view.viewport(), Qt.MouseButton.LeftButton, pos=press + QPoint(2, 0))
    qtbot.waitUntil(lambda: len(view.crossings) == 0, timeout=10_000)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)


def test_a_loaded_boundary_that_crosses_itself_is_refused_with_where(window, qtbot, tmp_path):
    t = np.linspace(0, 2 * np.pi, 80, endpoint=False)
    path = tmp_path / "eight.csv"
    rows = np.column_stack([np.cos(t), 0.3 * np.sin(2 * t), np.zeros(80)])
    path.write_text("\n".join(",".join(f"{v:.6f}" for v in row) for row in rows) + "\n")
    leaf = window.session.state.leaf
    with qtbot.waitSignal(window.failure_shown, timeout=30_000):
        window.open_path(str(path))  # read off the main thread
    assert "crosses itself near" in window.last_error_box.text()
    assert window.session.state.leaf is leaf
    window.last_error_box.close()


def test_vein_colours_match_between_the_views(window):
    names = window.viewport.actor_names("points")
    for i in range(len(window.session.result.leaf.veins)):
        actor = window.viewport.plotter.actors[f"points:vein{i}"]
        assert f"points:vein{i}" in names
        expected = QColor(vein_color(i))
        got = [round(c * 255) for c in actor.prop.color.float_rgb]
        assert got == [expected.red(), expected.green(), expected.blue()]
    assert len(window.editor.view.sketch.veins) == len(window.session.result.leaf.veins)


def test_a_parameter_change_is_undone_and_redone_with_ctrl_y(window, qtbot):
    assert QKeySequence("Ctrl+Y") in window.actions["edit.redo"].shortcuts()
    assert QKeySequence("Ctrl+Shift+Z") in window.actions["edit.redo"].shortcuts()
    k = window.panel.k.value()
    window.panel.k.setValue(k + 4)
    assert window.actions["edit.undo"].isEnabled() and "K" in window.actions["edit.undo"].text()
    assert window.isWindowModified()
    window.actions["edit.undo"].trigger()
    assert window.panel.k.value() == k and window.session.params.k == k
    wait_result(qtbot, window, lambda o: o.result.params.k == k)
    window.actions["edit.redo"].trigger()
    assert window.panel.k.value() == k + 4


def test_a_new_result_updates_the_drawn_actors_in_place(window, qtbot):
    mesh = window.viewport.plotter.actors["mesh"]
    vein = window.viewport.plotter.actors["points:vein0"]
    window.panel.seed.setValue(window.panel.seed.value() + 1)
    wait_result(qtbot, window, lambda o: o.result.params.seed == window.panel.seed.value())
    assert window.viewport.plotter.actors["mesh"] is mesh  # no new actor, mapper or lookup table
    assert window.viewport.plotter.actors["points:vein0"] is vein
    assert mesh.mapper.dataset.n_points == window.session.result.mesh.n_points


def test_point_sizes_follow_the_pixel_ratio(window, qtbot, monkeypatch):
    size = window.viewport.plotter.actors["points:vein0"].prop.point_size
    monkeypatch.setattr(window.viewport, "pixel_ratio", lambda: 2.0)
    window.viewport.clear()  # draw again from scratch at ratio 2
    window.panel.seed.setValue(window.panel.seed.value() + 1)
    wait_result(qtbot, window, lambda o: o.result.params.seed == window.panel.seed.value())
    assert window.viewport.plotter.actors["points:vein0"].prop.point_size == 2 * size


def test_a_dark_palette_darkens_the_canvas_and_the_3d_background(window):
    dark = QPalette()
    for role, color in (
        (QPalette.ColorRole.Window, "#202124"),
        (QPalette.ColorRole.Base, "#17181a"),
        (QPalette.ColorRole.Text, "#e8e8e8"),
        (QPalette.ColorRole.WindowText, "#e8e8e8"),
    ):
        dark.setColor(role, QColor(color))
    window.setPalette(dark)
    background = window.editor.view.backgroundBrush().color()
    assert background.lightnessF() < 0.3
    bottom = window.viewport.plotter.renderer.GetBackground()
    assert max(bottom) < 0.3
    outline = window.viewport.plotter.actors["points:boundary"].prop.color
    assert min(outline.float_rgb) > 0.7  # the boundary's dots turn light on a dark background


def test_mirror_editing_adds_the_reflected_point_and_a_profile_is_one_step(window, qtbot):
    window.new_sketch()
    view = window.editor.view
    qtbot.mouseClick(window.editor.new_vein, Qt.MouseButton.LeftButton)
    for x in (0.05, 0.95):
        click(qtbot, view, (x, 0.0))
    window.editor.mirror.setChecked(True)
    window.editor.curve.setCurrentIndex(0)
    window.editor.curve.activated.emit(0)  # back to the boundary
    for xy in ((0.0, 0.0), (0.3, 0.15), (0.7, 0.15), (1.0, 0.0)):
        click(qtbot, view, xy)
    boundary = view.sketch.boundary
    assert len(boundary) == 6  # the two off-axis clicks gained mirror images
    assert np.isclose(boundary[:, 1].min(), -0.15, atol=0.01)
    steps = window.session.history.count()
    window.editor.curve.setCurrentIndex(1)
    window.editor.curve.activated.emit(1)
    window.editor.profile_start.setValue(0.06)
    window.editor.profile_end.setValue(0.01)
    qtbot.mouseClick(window.editor.profile, Qt.MouseButton.LeftButton)
    np.testing.assert_allclose(view.sketch.veins[0][:, 2], [0.06, 0.01])
    assert window.session.history.count() == steps + 1
    assert window.session.history.undo_text() == "Vein profile"
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)


def test_a_scan_opened_after_another_is_framed_on_its_own_blade(window, qtbot, tmp_path):
    from tests.gui.builders import six_column_scan, write_points

    first = six_column_scan()
    second = six_column_scan(seed=1)
    second[:, :3] = second[:, :3] * 3.0 + [20.0, -5.0, 2.0]  # elsewhere, three times larger
    rng = np.random.default_rng(2)
    outliers = rng.uniform(-40, 80, size=(6, 3))  # far stray points in the second scan
    second = np.vstack([second, np.column_stack([outliers, np.tile([0, 0, 1.0], (6, 1))])])
    for i, rows in enumerate((first, second)):
        path = write_points(tmp_path / f"scan{i}.txt", rows)
        window.session.history.set_clean()
        assert window.open_path(path)
        qtbot.waitUntil(lambda p=path: window.session.state.path == p, timeout=60_000)
        wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
        wide, high = leaf_fill(window)
        assert max(wide, high) >= 0.6 and min(wide, high) >= 0.35, (i, wide, high)
