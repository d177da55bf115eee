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
    monkeypatch.setattr(QInputDialog, "getInt", lambda *a, **k: (0, True))
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


def _answer_photo_dialog(monkeypatch, answer) -> None:
    """File > Open photo's dialog answered by `answer(dialog)` instead of a user."""
    from leafstudio.gui.qt.photo_dialog import PhotoDialog

    def fake_exec(dialog: PhotoDialog) -> int:
        answer(dialog)
        dialog.try_accept()
        return dialog.result()

    monkeypatch.setattr(PhotoDialog, "exec", fake_exec)


@pytest.fixture
def oak(tmp_path, monkeypatch):
    from leafstudio.forms import make_form
    from tests.photos import form_photo

    form = make_form("ovate")
    image, _, _ = form_photo(form.boundary, form.veins, petiole=0.15, angle=30)
    path = tmp_path / "oak.png"
    Image.fromarray(image).save(path)
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(path), ""))
    return path


def test_open_photo_asks_the_leafs_length(window, qtbot, oak, monkeypatch):
    _answer_photo_dialog(monkeypatch, lambda dialog: dialog.length.setText("8cm"))
    window.open_photo_dialog()
    qtbot.waitUntil(lambda: window.session.state.path == str(oak), timeout=WAIT_MS)
    wait_result(qtbot, window, lambda outcome: outcome.result.leaf is window.session.state.leaf)
    boundary = window.session.state.leaf.boundary
    assert np.ptp(boundary[:, 0]) == pytest.approx(80, rel=0.03)  # millimetres, base to apex
    assert window.settings.value("export/length") == "8cm"  # the export offers its real size

    _answer_photo_dialog(monkeypatch, lambda dialog: dialog.length.setText("eight"))
    window.open_photo_dialog()  # refused in the dialog, the leaf kept
    assert "length" in window.photo_dialog.summary.text()
    assert window.session.state.path == str(oak)


def test_open_photo_takes_a_ruler_clicked_on_the_photo(window, qtbot, oak, monkeypatch):
    """Two clicks on the photo 50 mm apart: the leaf (360 photo pixels long) at its real size."""
    from PySide6.QtCore import QPoint, Qt

    def ruler(dialog) -> None:
        picture = dialog.picture
        ends = (20, 200), (20 + round(360 * picture.zoom), 200)  # 360 photo pixels apart
        for x, y in ends:
            qtbot.mouseClick(picture, Qt.MouseButton.LeftButton, pos=QPoint(x, y))
        dialog.length.setText("")
        dialog.distance.setText("50 mm")
        assert "pixels are 50 mm" in dialog.summary.text()

    _answer_photo_dialog(monkeypatch, ruler)
    window.open_photo_dialog()
    ruler_pixels = window.photo_dialog.model.ruler_pixels()
    assert ruler_pixels == pytest.approx(360, abs=2)
    qtbot.waitUntil(lambda: window.session.state.path == str(oak), timeout=WAIT_MS)
    length = float(np.max(window.session.state.leaf.boundary[:, 0]))
    assert length == pytest.approx(50 * 360 / ruler_pixels, rel=0.03)  # millimetres
    qtbot.waitUntil(lambda: window.settings.value("export/length", "").endswith("mm"),
                    timeout=WAIT_MS)  # fmt: skip
    assert float(window.settings.value("export/length")[:-2]) == pytest.approx(length, rel=1e-3)


def test_the_photo_dialog_shows_a_portrait_photo_upright(qtbot, tmp_path):
    """A phone's portrait photo (pixels stored sideways, EXIF orientation 6) showed on its side
    in File > Open photo's dialog; it shows upright, as the leaf is found in it."""
    from leafstudio.forms import make_form
    from leafstudio.gui.model.photo_import import PhotoImport
    from leafstudio.gui.qt.photo_dialog import PhotoDialog
    from tests.photos import exif_turned, form_photo

    form = make_form("ovate")
    upright = form_photo(form.boundary, form.veins, angle=90, size=(500, 760))[0]  # portrait
    dialog = PhotoDialog(PhotoImport.of(str(exif_turned(upright, tmp_path / "p.jpg"))))
    qtbot.addWidget(dialog)
    shown = dialog.picture.photo
    assert shown.height() > shown.width()
    assert dialog.picture.zoom == pytest.approx(shown.width() / 500, rel=1e-3)


def test_open_photo_names_the_base_end(window, qtbot, tmp_path, monkeypatch):
    """The dialog's Base choice reaches the leaf as `photo --base-end` does: an obovate leaf
    without visible veins, base on the left, comes out obovate (widest toward its apex)."""
    from leafstudio.forms import make_form
    from leafstudio.sources.photo import BASE_ENDS
    from tests.photos import form_photo

    path = tmp_path / "obovate.png"
    Image.fromarray(form_photo(make_form("obovate").boundary, angle=0.0)[0]).save(path)
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(path), ""))
    _answer_photo_dialog(
        monkeypatch, lambda dialog: dialog.base_end.setCurrentIndex(BASE_ENDS.index("left"))
    )
    window.open_photo_dialog()
    assert "left end" in window.photo_dialog.summary.text()
    qtbot.waitUntil(lambda: window.session.state.path == str(path), timeout=WAIT_MS)
    boundary = window.session.state.leaf.boundary
    assert boundary[np.argmax(np.abs(boundary[:, 1])), 0] > 0.5 * np.max(boundary[:, 0])


def test_photo_lengths():
    assert photo_length("8cm") == 80 and photo_length("0.08m") == 80 and photo_length("") is None
    assert photo_length("3") == 3 and has_unit("80mm") and not has_unit("2.5")
    for bad in ("-1", "0", "nan", "8 parsecs"):
        with pytest.raises(LeafError):
            photo_length(bad)


def test_the_export_dialog_offers_levels_of_detail(window, qtbot, tmp_path, monkeypatch):
    pytest.importorskip("open3d")
    ply = tmp_path / "leaf.ply"
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(ply), ""))
    monkeypatch.setattr(QInputDialog, "getText", lambda *a, **k: ("", True))
    monkeypatch.setattr(QInputDialog, "getInt", lambda *a, **k: (2, True))
    window.export_mesh_dialog()
    exports_done(qtbot, window)
    faces = [len(trimesh.load(tmp_path / name, process=False).faces)
             for name in ("leaf.ply", "leaf_lod1.ply", "leaf_lod2.ply")]  # fmt: skip
    assert faces[0] > faces[1] > faces[2]  # each coarser than the one before
    assert window.settings.value("export/lod") in (2, "2")  # offered next time


def test_a_second_export_queued_behind_a_running_one_is_written_too(window, qtbot, tmp_path):
    """Three exports asked for at once: the worker used to replace the waiting second one with
    the third, silently; now they run in turn and the status line counts those waiting."""
    jobs = [window.save_mesh(str(tmp_path / f"leaf{i}.usda")) for i in range(3)]
    assert "(2 more queued)" in window.status_text.text()
    for job in jobs:
        assert exported(qtbot, job)
    assert all((tmp_path / f"leaf{i}.usda").exists() for i in range(3))
    assert window.status_text.text() == "Exported leaf2.usda"
    assert not window._export_bar.isVisible()
