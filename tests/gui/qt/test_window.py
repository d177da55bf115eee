"""The main window over the worker: results appear, sliders reconstruct off the main thread,
a slider storm runs the pipeline only a few times, files round-trip, bad files keep the leaf."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QMessageBox

from leafstudio.core.pipeline import Pipeline
from leafstudio.gui.model.layers import LAYERS
from leafstudio.gui.qt.main_window import MainWindow
from tests.gui.builders import FAST

from .conftest import close_window, exported, exports_done, make_window, wait_result


@pytest.fixture
def pipeline_calls(monkeypatch):
    """Records the thread of every Pipeline.run call."""
    calls: list[int] = []
    run = Pipeline.run

    def recording(self, *args, **kwargs):
        calls.append(threading.get_ident())
        return run(self, *args, **kwargs)

    monkeypatch.setattr(Pipeline, "run", recording)
    return calls


def mesh_actor_points(window: MainWindow) -> np.ndarray:
    actor = window.viewport.plotter.actors["mesh"]
    return np.asarray(actor.mapper.dataset.points)


def test_the_demo_result_appears(window, qtbot):
    result = window.session.result
    assert result is not None and result.mesh.n_points > 100
    assert "mesh" in window.viewport.plotter.actors
    assert len(mesh_actor_points(window)) == result.mesh.n_points
    qtbot.waitUntil(lambda: window.measurements.topLevelItemCount() >= 3)
    assert "Leaf" in window.measurements.topLevelItem(0).text(0)
    # each stage's time under the short line: those that ran (none when an earlier test left
    # every stage in the cache), the drawing, and a word on the others
    tip = window.status_text.toolTip()
    assert all(f"{stage} " in tip for stage in result.timings) and "draw " in tip, tip
    assert "stages not listed came from the cache" in tip
    assert window.editor.view.sketch.boundary.shape[0] >= 3  # the leaf as an editable sketch


def test_k_slider_gives_a_new_mesh_computed_off_the_main_thread(window, qtbot, pipeline_calls):
    before = mesh_actor_points(window).copy()
    window.panel.k.setValue(6)
    outcome = wait_result(qtbot, window, lambda o: o.result.params.k == 6)
    after = mesh_actor_points(window)
    assert len(after) != len(before) or not np.allclose(after, before, atol=1e-6)
    assert pipeline_calls and threading.main_thread().ident not in pipeline_calls
    assert outcome.thread != threading.main_thread().ident
    assert "frame" not in outcome.result.ran and "gmm" in outcome.result.ran  # the cache held


def test_a_slider_storm_runs_a_few_times_and_shows_the_last_value(window, qtbot, pipeline_calls):
    values = [1 + (7 * i) % 12 for i in range(20)]
    for value in values:  # quicker than the throttle: one run at once, one for the last value
        window.panel.k.setValue(value)
    # the last value leaves the throttle after its timeout: the first run may be done before
    qtbot.waitUntil(lambda: window.session.params.k == values[-1], timeout=5_000)
    wait_result(qtbot, window, lambda o: o.request.id == window.session.last_id)
    assert 1 <= len(pipeline_calls) <= 3
    assert window.session.result.params.k == values[-1]
    assert len(mesh_actor_points(window)) == window.session.result.mesh.n_points


def test_layers_switch_on_and_off_and_actors_are_replaced_not_piled(window, qtbot):
    items = {
        window.layer_list.item(i).data(Qt.ItemDataRole.UserRole): window.layer_list.item(i)
        for i in range(window.layer_list.count())
    }
    assert set(items) == {key for key, _, _ in LAYERS}
    items["probability"].setCheckState(Qt.CheckState.Checked)
    items["mesh"].setCheckState(Qt.CheckState.Unchecked)
    actors = window.viewport.plotter.actors
    assert actors["probability"].GetVisibility() and not actors["mesh"].GetVisibility()
    assert "p(x)" in window.viewport.plotter.scalar_bars
    assert "height" not in window.viewport.plotter.scalar_bars
    counts = []
    for seed in (3, 4):
        window.panel.seed.setValue(seed)
        wait_result(qtbot, window, lambda o, s=seed: o.result.params.seed == s)
        counts.append(len(window.viewport.plotter.actors))
    assert counts[0] == counts[1]
    assert "mesh" not in window.viewport.plotter.actors  # hidden layers are drawn when shown
    window.edges.setChecked(True)
    items["mesh"].setCheckState(Qt.CheckState.Checked)
    assert window.viewport.plotter.actors["mesh"].prop.show_edges
    window.coloring.setCurrentIndex(window.coloring.findData("mean_curvature"))
    mesh = window.viewport.plotter.actors["mesh"]
    assert mesh.mapper.array_name == "mean_curvature" and mesh.prop.show_edges
    low, high = mesh.mapper.scalar_range
    assert low == -high and high > 0  # curvature colours centred on 0
    assert "mean curvature" in window.viewport.plotter.scalar_bars
    assert "height" not in window.viewport.plotter.scalar_bars


def test_save_reopen_and_compare(window, qtbot, tmp_path):
    window.panel.k.setValue(4)
    wait_result(qtbot, window, lambda o: o.result.params.k == 4)
    leaf, params, mesh = (
        window.session.state.leaf,
        window.panel.params(),
        window.session.result.mesh,
    )
    path = tmp_path / "saved.leaf.json"
    assert window.save_to(str(path))
    assert not window.isWindowModified()

    other = make_window(qtbot, tmp_path / "other.ini")
    assert other.open_path(str(path))
    wait_result(qtbot, other)
    assert other.panel.params() == params
    np.testing.assert_allclose(other.session.state.leaf.boundary, leaf.boundary)
    assert len(other.session.state.leaf.veins) == len(leaf.veins)
    np.testing.assert_allclose(other.session.result.mesh.points, mesh.points, atol=1e-9)
    assert str(path.resolve()) in other.recent_files()
    close_window(other)


def test_a_bad_file_shows_an_error_and_keeps_the_mesh(window, qtbot, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y,z\n1,2\n")
    leaf, points = window.session.state.leaf, mesh_actor_points(window).copy()
    with qtbot.waitSignal(window.failure_shown, timeout=30_000):
        window.open_path(str(bad))  # read off the main thread
    box = window.last_error_box
    assert box is not None and box.isVisible() and "bad.csv" in box.text()
    assert "line 2" in box.text()
    box.close()
    assert window.session.state.leaf is leaf
    np.testing.assert_array_equal(mesh_actor_points(window), points)


def test_a_leaf_that_cannot_be_reconstructed_keeps_the_old_one(window, qtbot, tmp_path):
    line = tmp_path / "line.csv"
    line.write_text("\n".join(f"{t},{2 * t},0" for t in np.linspace(0, 1, 20)) + "\n")
    leaf, result = window.session.state.leaf, window.session.result
    with qtbot.waitSignal(window.failure_shown, timeout=30_000) as failure:
        assert window.open_path(str(line))
    assert "line" in failure.args[0]
    assert window.session.state.leaf is leaf and window.session.result is result
    assert window.session.state.path is None  # still the demo
    assert "line" in window.last_error_box.text()
    window.last_error_box.close()


def test_unsaved_changes_are_asked_about_before_closing(window, qtbot, monkeypatch):
    view = window.editor.view
    view.delete_selected()  # nothing selected: no edit
    assert not window.isWindowModified()
    view.selected = (-1, 0)
    view.delete_selected()
    assert window.isWindowModified()
    asked = []
    monkeypatch.setattr(
        QMessageBox,
        "question",
        lambda *a, **k: asked.append(a) or QMessageBox.StandardButton.Cancel,
    )
    assert not window.close()
    assert asked and window.isVisible()


def test_parameters_and_layers_are_remembered(qtbot, tmp_path):
    first = make_window(qtbot, tmp_path / "s.ini")
    first.panel.set_params(FAST.with_(k=7, seed=11))
    first.layer_list.item(2).setCheckState(Qt.CheckState.Checked)
    close_window(first)
    second = make_window(qtbot, tmp_path / "s.ini")
    assert second.panel.params() == second.session.params == FAST.with_(k=7, seed=11)
    assert second.layer_list.item(2).checkState() == Qt.CheckState.Checked
    close_window(second)


def test_export_mesh_and_open_by_drag_and_drop(window, qtbot, tmp_path):
    import pyvista as pv
    from PySide6.QtCore import QMimeData, QPointF, QUrl
    from PySide6.QtGui import QDropEvent

    for suffix in (".ply", ".vtp"):
        out = tmp_path / f"leaf{suffix}"
        assert exported(qtbot, window.save_mesh(str(out)))
        assert pv.read(out).n_points == window.session.result.mesh.n_points
    assert not window.save_mesh(str(tmp_path / "leaf.xyz"))  # not a mesh type: an error box
    window.last_error_box.close()

    dropped = tmp_path / "dropped.leaf.json"
    window.save_to(str(dropped))
    before = window.session.state.leaf
    mime = QMimeData()
    mime.setUrls([QUrl.fromLocalFile(str(dropped))])
    event = QDropEvent(
        QPointF(10, 10),
        Qt.DropAction.CopyAction,
        mime,
        Qt.MouseButton.NoButton,
        Qt.KeyboardModifier.NoModifier,
    )
    window.dropEvent(event)  # read off the main thread
    qtbot.waitUntil(lambda: window.session.state.leaf is not before, timeout=30_000)
    assert window.session.state.path == str(dropped)
    np.testing.assert_allclose(window.session.state.leaf.boundary, before.boundary)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)


def test_export_a_textured_gltf_and_a_solid(window, qtbot, tmp_path):
    import trimesh

    glb = tmp_path / "leaf.glb"
    assert exported(qtbot, window.save_mesh(str(glb)))
    (mesh,) = trimesh.load(glb, process=False).geometry.values()
    assert mesh.visual.material.baseColorTexture is not None and mesh.visual.uv is not None
    solid = tmp_path / "leaf.stl"
    assert exported(qtbot, window.save_mesh(str(solid), thickness="0.01"))
    assert trimesh.load(solid).is_watertight
    assert not window.save_mesh(str(tmp_path / "bad.stl"), thickness="thick")  # an error box
    window.last_error_box.close()
    assert not (tmp_path / "bad.stl").exists()


def test_open_a_photo_finds_the_leaf_and_reconstructs_it(window, qtbot, tmp_path):
    from PIL import Image

    from leafstudio.forms import make_form
    from tests.photos import form_photo

    leaf = make_form("ovate")
    image, _, _ = form_photo(leaf.boundary, leaf.veins, petiole=0.2, angle=30)
    photo = tmp_path / "leaf.png"
    Image.fromarray(image).save(photo)
    assert window.open_path(str(photo))
    qtbot.waitUntil(lambda: window.session.state.path == str(photo), timeout=60_000)
    wait_result(qtbot, window, lambda outcome: outcome.result.leaf is window.session.state.leaf)
    found = window.session.state.leaf
    assert np.ptp(found.boundary[:, 0]) == pytest.approx(1.0, abs=0.05)  # base 0, apex at 1
    assert len(found.veins) >= 3  # grown
    blank = tmp_path / "blank.png"
    Image.new("RGB", (200, 150), (230, 230, 230)).save(blank)
    with qtbot.waitSignal(window.failure_shown, timeout=60_000) as failed:
        window.open_path(str(blank))
    assert "no leaf found" in failed.args[0]
    window.last_error_box.close()
    assert window.session.state.leaf is found  # the current leaf is kept


def test_the_export_dialog_offers_the_texture(window, qtbot, tmp_path, monkeypatch):
    """Issue 14: `--texture auto|none|IMAGE`, and the same in the app's export dialog."""
    import trimesh
    from PIL import Image
    from PySide6.QtWidgets import QFileDialog, QInputDialog

    photo = tmp_path / "bark.png"
    Image.new("RGB", (64, 48), (200, 30, 10)).save(photo)
    glb = tmp_path / "leaf.glb"
    choices = iter([(window.TEXTURE_CHOICES[2], True), (window.TEXTURE_CHOICES[1], True)])
    monkeypatch.setattr(QInputDialog, "getItem", lambda *a, **k: next(choices))
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(glb), ""))
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(photo), ""))
    monkeypatch.setattr(QInputDialog, "getText", lambda *a, **k: ("", True))  # its own units
    monkeypatch.setattr(QInputDialog, "getInt", lambda *a, **k: (0, True))  # no levels of detail
    window.export_mesh_dialog()  # an image file
    exports_done(qtbot, window)
    (mesh,) = trimesh.load(glb, process=False).geometry.values()
    image = np.asarray(mesh.visual.material.baseColorTexture.convert("RGB")).reshape(-1, 3)
    assert np.all(np.abs(np.median(image, axis=0) - [200, 30, 10]) <= 12)  # the image's colour
    window.export_mesh_dialog()  # none
    exports_done(qtbot, window)
    (mesh,) = trimesh.load(glb, process=False).geometry.values()
    assert mesh.visual.material.baseColorTexture is None and mesh.visual.uv is not None
    assert not window.save_mesh(str(glb), texture=str(tmp_path / "missing.png"))  # an error box
    window.last_error_box.close()
