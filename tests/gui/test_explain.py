"""The app explains itself: a Steps view through the pipeline's layers, exports for slides."""

from __future__ import annotations

from PySide6.QtCore import Qt

from leafstudio.gui import explain
from tests.gui.conftest import wait_result


def _checked(window) -> set[str]:
    layers = window.layer_list
    return {
        layers.item(i).data(Qt.ItemDataRole.UserRole)
        for i in range(layers.count())
        if layers.item(i).checkState() == Qt.CheckState.Checked
    }


def test_steps_view_walks_through_the_layers_and_puts_them_back(window, qtbot):
    before = _checked(window)
    dialog = explain.StepsDialog(window)
    qtbot.addWidget(dialog)
    seen = []
    for _ in explain.STEPS:
        seen.append((_checked(window) - {"scan"}, dialog.caption.text()))
        dialog.next.click()
    assert [layers for layers, _ in seen] == [set(s[2]) for s in explain.STEPS]
    assert all(caption for _, caption in seen)
    assert not dialog.next.isEnabled()
    dialog.close()
    assert _checked(window) == before


def test_export_turntable_and_steps_figure(window, qtbot, tmp_path):
    wait_result(qtbot, window)
    explain.install(window)
    layers = window.layer_list
    assert all(layers.item(i).toolTip() for i in range(layers.count()))  # every layer explained
    texts = [a.text() for a in window.menuBar().actions()[0].menu().actions()]
    assert any("turntable" in t for t in texts) and any("steps" in t for t in texts)
    assert explain.export_slide(window, "turntable", str(tmp_path / "t.gif"))
    assert explain.export_slide(window, "steps", str(tmp_path / "s.png"))
    assert (tmp_path / "t.gif").stat().st_size > 1000 and (tmp_path / "s.png").stat().st_size > 1000
    assert not explain.export_slide(window, "turntable", str(tmp_path / "t.avi"))  # a message
