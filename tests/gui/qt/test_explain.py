"""The app explains itself: a tooltip per layer, view aids, exports for slides."""

from __future__ import annotations

from leafstudio.gui.qt import explain
from tests.gui.qt.conftest import exported, wait_result


def test_export_turntable_and_steps_figure(window, qtbot, tmp_path):
    wait_result(qtbot, window)
    if not hasattr(window, "view_aids"):  # the window installs it (main_window.py)
        explain.install(window)
    layers = window.layer_list
    assert all(layers.item(i).toolTip() for i in range(layers.count()))  # every layer explained
    texts = [a.text() for a in window.menuBar().actions()[0].menu().actions()]
    assert any("turntable" in t for t in texts) and any("steps" in t for t in texts)
    job = explain.export_slide(window, "turntable", str(tmp_path / "t.gif"))
    assert exported(qtbot, job)  # in the export process
    assert exported(qtbot, explain.export_slide(window, "steps", str(tmp_path / "s.png")))
    assert (tmp_path / "t.gif").stat().st_size > 1000 and (tmp_path / "s.png").stat().st_size > 1000
    assert not explain.export_slide(window, "turntable", str(tmp_path / "t.avi"))  # a message


def test_height_exaggeration_kept_colours_and_k_in_the_view(window, qtbot):
    wait_result(qtbot, window)
    if not hasattr(window, "view_aids"):  # the window installs it (main_window.py)
        explain.install(window)
    aids = window.view_aids
    plotter = window.viewport.plotter
    mesh = plotter.actors["mesh"]
    z_before = mesh.GetBounds()[5] - mesh.GetBounds()[4]
    aids.exaggeration.setValue(5.0)
    z_after = plotter.actors["mesh"].GetBounds()[5] - plotter.actors["mesh"].GetBounds()[4]
    assert z_after > 3 * z_before  # the demo lies in z = 0: its normal is z
    assert "k_label" in plotter.actors
    aids.keep.setChecked(True)
    kept = tuple(plotter.actors["mesh"].mapper.scalar_range)
    window.panel.k.setValue(5)
    wait_result(qtbot, window, lambda o: o.result.params.k == 5)
    assert tuple(plotter.actors["mesh"].mapper.scalar_range) == kept
    assert plotter.actors["mesh"].GetUserMatrix() is not None  # still exaggerated
    window.coloring.setCurrentIndex(window.coloring.findData("mean_curvature"))
    assert plotter.actors["mesh"].GetUserMatrix() is not None  # a new colouring keeps it
    aids.exaggeration.setValue(1.0)
    assert plotter.actors["mesh"].GetUserMatrix() is None
    aids.see_through.setChecked(True)
    assert plotter.actors["mesh"].prop.opacity < 0.5  # the layers under it show
    aids.see_through.setChecked(False)
    assert plotter.actors["mesh"].prop.opacity == 1.0
