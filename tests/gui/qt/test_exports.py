"""Issue 23: exporting froze the window (File > Export as .glb: 2.2 s), and the app had no
field for a leaf's real length (the command line has --length). Exports now run on the worker's
export lane with their progress in the status bar; the export dialogs and File > Open photo ask
for the length."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from PIL import Image
from PySide6.QtWidgets import QFileDialog, QInputDialog

from leafstudio.errors import LeafError
from leafstudio.gui.model.opening import has_unit, photo_length

from .conftest import WAIT_MS, exported, exports_done, wait_result


def test_an_export_returns_at_once_and_reports_its_progress(window, qtbot, tmp_path):
    seen: list[float] = []
    window.export_progress.connect(lambda fraction, _what: seen.append(fraction))
    job = window.save_mesh(str(tmp_path / "leaf.usda"), length="8cm")  # USD: the slowest kind
    assert job is not None and not job.finished  # written on the export lane, not here
    assert window._export_bar.isVisible()
    assert exported(qtbot, job)
    qtbot.waitUntil(lambda: seen and seen[-1] == 1.0, timeout=WAIT_MS)
    assert seen == sorted(seen) and len(seen) >= 4  # the mesh, textures, placing, writing, done
    assert not window._export_bar.isVisible()
    assert window.status_text.text() == "Exported leaf.usda"


def test_a_failed_export_says_why_in_the_window(window, qtbot, tmp_path):
    (tmp_path / "leaf.glb").mkdir()  # a folder where the file would go
    job = window.save_mesh(str(tmp_path / "leaf.glb"))
    qtbot.waitUntil(lambda: job.finished, timeout=WAIT_MS)
    assert not job.succeeded
    assert "leaf.glb" in window.last_error_box.windowTitle() + window.last_error_box.text()
    window.last_error_box.close()
    assert window.status_text.text() == "Not exported: leaf.glb"


def test_the_export_dialog_takes_a_real_length(window, qtbot, tmp_path, monkeypatch):
    glb = tmp_path / "leaf.glb"
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(glb), ""))
    monkeypatch.setattr(QInputDialog, "getItem", lambda *a, **k: (window.TEXTURE_CHOICES[1], True))
    monkeypatch.setattr(QInputDialog, "getText", lambda *a, **k: ("8cm", True))
    window.export_mesh_dialog()
    exports_done(qtbot, window)
    mesh = trimesh.load(glb, force="mesh", process=False)
    assert mesh.extents[0] == pytest.approx(0.08, rel=1e-6)  # base to apex along +X, metres
    assert window.settings.value("export/length") == "8cm"  # offered next time

    stl = tmp_path / "solid.stl"
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(stl), ""))
    answers = iter([("0.5mm", True), ("8cm", True)])  # the thickness, then the length
    monkeypatch.setattr(QInputDialog, "getText", lambda *a, **k: next(answers))
    window.export_solid_dialog()
    exports_done(qtbot, window)
    solid = trimesh.load(stl)
    assert solid.is_watertight and solid.extents.max() == pytest.approx(80, rel=0.02)  # mm
    assert solid.volume == pytest.approx(solid.area / 2 * 0.5, rel=0.05)  # 0.5 mm thick


def test_open_photo_asks_the_leafs_length(window, qtbot, tmp_path, monkeypatch):
    from leafstudio.forms import make_form
    from tests.photos import form_photo

    form = make_form("ovate")
    image, _, _ = form_photo(form.boundary, form.veins, petiole=0.15, angle=30)
    path = tmp_path / "oak.png"
    Image.fromarray(image).save(path)
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(path), ""))
    monkeypatch.setattr(QInputDialog, "getText", lambda *a, **k: ("8cm", True))
    window.open_photo_dialog()
    qtbot.waitUntil(lambda: window.session.state.path == str(path), timeout=WAIT_MS)
    wait_result(qtbot, window, lambda outcome: outcome.result.leaf is window.session.state.leaf)
    boundary = window.session.state.leaf.boundary
    assert np.ptp(boundary[:, 0]) == pytest.approx(80, rel=0.03)  # millimetres, base to apex
    assert window.settings.value("export/length") == "8cm"  # the export offers its real size

    monkeypatch.setattr(QInputDialog, "getText", lambda *a, **k: ("eight", True))
    window.open_photo_dialog()  # refused in the window, the leaf kept
    assert "length" in window.last_error_box.text()
    window.last_error_box.close()
    assert window.session.state.path == str(path)


def test_photo_lengths():
    assert photo_length("8cm") == 80 and photo_length("0.08m") == 80 and photo_length("") is None
    assert photo_length("3") == 3 and has_unit("80mm") and not has_unit("2.5")
    for bad in ("-1", "0", "nan", "8 parsecs"):
        with pytest.raises(LeafError):
            photo_length(bad)
