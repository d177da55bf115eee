"""Framing beside the colour bars, and a drawn leaf's iso view once it has grown (issue 12:
every new leaf fills most of the view, the blade clear of the bars along the view's bottom)."""

from __future__ import annotations

import numpy as np
import pytest

from leafstudio.gui.model.framing import best_iso, blade_bounds, fit_camera, project, projected_fill
from leafstudio.gui.qt.view_camera import BAR_BAND

from .conftest import wait_result
from .test_drawing import camera, click, ellipse_clicks, leaf_fill


@pytest.mark.parametrize("name", ["nested", "parallel"])
def test_a_camera_keeping_the_bottom_free_frames_the_blade_above_it(name, demo_result):
    result = demo_result(name)
    bounds = blade_bounds(result.triangle_mesh.points, result.frame)
    for aspect in (0.8, 1.3, 1.8):
        direction, up = best_iso(bounds, 30.0, aspect, BAR_BAND)
        camera = fit_camera(bounds, direction, up, 30.0, aspect, bottom=BAR_BAND)
        _, y = project(bounds.extent_points(), *camera, 30.0, aspect)
        assert y.min() >= -1 + 2 * BAR_BAND - 1e-9 and y.max() <= 1
        assert abs((y.min() + y.max()) / 2 - BAR_BAND) < 0.01  # centred in the free part
        wide, high = projected_fill(bounds, *camera, 30.0, aspect)
        assert max(wide, high) >= 0.6 and min(wide, high) >= 0.35, (aspect, wide, high)


def _display_heights(window) -> np.ndarray:
    """Display y of the mesh's points as a share of the view's height (0 at its bottom)."""
    points = np.asarray(window.session.result.triangle_mesh.points)[::5]
    height = window.viewport.plotter.renderer.GetSize()[1]
    return window.viewport.display_points(points)[:, 1] / height


def test_the_leaf_is_framed_clear_of_the_height_colour_bar(window, qtbot):
    window.coloring.setCurrentIndex(window.coloring.findData("height"))  # (the Leaf look has none)
    assert window.viewport.plotter.scalar_bars  # the height bar along the bottom
    for name in ("nested", "parallel"):
        window.open_demo(name)
        wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
        assert np.quantile(_display_heights(window), 0.01) >= BAR_BAND - 0.01, name


def test_a_drawn_leaf_gets_the_iso_view_of_the_whole_leaf_unless_the_user_turned_it(window, qtbot):
    window.new_sketch()
    view = window.editor.view
    for xy in ellipse_clicks()[[0, 4, 8]]:  # a sliver first: its own best iso
        click(qtbot, view, xy)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    for xy in ellipse_clicks()[[1, 2, 3, 5, 6, 7, 9, 10, 11]]:
        click(qtbot, view, xy)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    plotter = window.viewport.plotter
    grown = camera(window)
    window.viewport.camera("iso")  # what the Iso button shows for the whole leaf
    np.testing.assert_allclose(grown, camera(window), atol=1e-9)
    wide, high = leaf_fill(window)
    assert max(wide, high) >= 0.6 and min(wide, high) >= 0.35, (wide, high)

    window.new_sketch()  # again, but the user turns the view after the sliver
    for xy in ellipse_clicks()[[0, 4, 8]]:
        click(qtbot, view, xy)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    plotter.camera.azimuth = 40.0
    turned = np.asarray(plotter.camera.position) - np.asarray(plotter.camera.focal_point)
    for xy in ellipse_clicks()[[1, 2, 3, 5, 6, 7, 9, 10, 11]]:
        click(qtbot, view, xy)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    now = np.asarray(plotter.camera.position) - np.asarray(plotter.camera.focal_point)
    cosine = now @ turned / np.linalg.norm(now) / np.linalg.norm(turned)
    assert cosine > 1 - 1e-9  # the user's direction kept, the leaf refitted along it
