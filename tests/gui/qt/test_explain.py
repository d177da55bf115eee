"""The app explains itself: a tooltip per layer, view aids, exports for slides."""

from __future__ import annotations

import numpy as np

from leafstudio.gui.qt import explain
from leafstudio.model import Leaf
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


def test_a_posed_leaf_is_drawn_unstretched_with_a_note_and_a_flat_blades_k_is_unused(window, qtbot):
    """appreview31, findings 4 and 8: Height × 3 stretched ovate curled 1 along its flat blade's
    normal (its midrib drawn 2.37 long instead of 0.99): a posed leaf is now drawn as it is,
    Height × saying why; and a blade with no relief of its own read "K = 1" beside a K of 3."""
    from leafstudio.core.bend import Pose
    from leafstudio.forms import Form
    from leafstudio.gui.model.view_aids import FLAT_K

    wait_result(qtbot, window)
    aids = window.view_aids
    plotter = window.viewport.plotter
    window.session.new_document(Form("ovate", curl=1.0).leaf(), title="ovate curled")
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
    aids.exaggeration.setValue(3.0)
    assert plotter.actors["mesh"].GetUserMatrix() is None
    assert aids.stretch_note.isVisibleTo(aids)
    aids.exaggeration.setValue(1.0)
    assert not aids.stretch_note.isVisibleTo(aids)
    t = np.linspace(0, 2 * np.pi, 80, endpoint=False)
    boundary = np.column_stack([0.5 + 0.5 * np.cos(t), 0.2 * np.sin(t), 0 * t])
    midrib = np.column_stack([np.linspace(0.02, 0.98, 12), np.zeros(12), np.zeros(12)])
    window.session.new_document(Leaf(boundary, [midrib]), title="flat")
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
    window.session.set_bend(Pose(fold=45.0))
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
    assert aids._label[0] == FLAT_K and window.panel.k.value() == 3
    aids.exaggeration.setValue(3.0)  # the drawn leaf bent by the sliders: not stretched either
    assert plotter.actors["mesh"].GetUserMatrix() is None and aids.stretch_note.isVisibleTo(aids)
    aids.exaggeration.setValue(1.0)


def test_the_status_line_says_the_k_used_on_a_flat_blade(window, qtbot):
    """closing32: a flat blade fits no mixture (Result.fitted_k None), yet the status line
    said "K=3", the K asked for, beside the view's "K unused (flat blade)"."""
    from leafstudio.gui.model.view_aids import FLAT_K

    wait_result(qtbot, window)
    assert window.status_text.text().startswith("K = 3,")  # the demo: a mixture of 3
    t = np.linspace(0, 2 * np.pi, 80, endpoint=False)
    boundary = np.column_stack([0.5 + 0.5 * np.cos(t), 0.2 * np.sin(t), 0 * t])
    midrib = np.column_stack([np.linspace(0.02, 0.98, 12), np.zeros(12), np.zeros(12)])
    window.session.new_document(Leaf(boundary, [midrib]), title="flat")
    outcome = wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
    assert outcome.result.fitted_k is None and window.panel.k.value() == 3
    qtbot.waitUntil(lambda: "shown in" in window.status_text.text())
    assert window.status_text.text().startswith(f"{FLAT_K}, grid")
    assert "K=3" not in window.status_text.text()
