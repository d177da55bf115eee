"""Findings of a teacher's and a new user's first hour (issues 22 and 24): the first-start
layout, the gallery's names and words, stale failures, the Poisson layer without open3d, and
undo from a parameter field."""

from __future__ import annotations

import itertools
import re
import sys
from dataclasses import replace

import numpy as np
import pytest
from PySide6.QtCore import QSettings, Qt

from leafstudio.gui.qt.forms_dock import FormsPanel
from tests.gui.qt.conftest import WAIT_MS, close_window, image_pixels, make_window


def _shown(dock) -> bool:
    """The dock is on screen and not a tab hidden behind another."""
    return dock.isVisible() and not dock.visibleRegion().isEmpty() and dock.widget().isVisible()


def test_a_fresh_start_shows_the_forms_dock_and_a_saved_layout_is_kept(qtbot, tmp_path):
    window = make_window(qtbot, tmp_path / "fresh.ini")
    qtbot.waitUntil(lambda: _shown(window.docks["Sketch"]))
    assert _shown(window.docks["Forms"]) and _shown(window.docks["Sketch"])
    # a user who had tabbed Forms behind Sketch finds it so again
    window.tabifyDockWidget(window.docks["Sketch"], window.docks["Forms"])
    window.docks["Sketch"].raise_()
    qtbot.waitUntil(lambda: not _shown(window.docks["Forms"]))
    close_window(window)
    again = make_window(qtbot, tmp_path / "fresh.ini")
    qtbot.waitUntil(lambda: _shown(again.docks["Sketch"]))
    assert not _shown(again.docks["Forms"])
    assert again.tabifiedDockWidgets(again.docks["Sketch"]) == [again.docks["Forms"]]
    assert QSettings(str(tmp_path / "fresh.ini"), QSettings.Format.IniFormat).contains(
        "window/state"
    )


def _gallery_rows(gallery, image, item) -> tuple[np.ndarray, np.ndarray]:
    """Rows (viewport pixels) of an item's drawn leaf (green) and of its name (grey text)."""
    rect = gallery.visualItemRect(item)
    pixels = image_pixels(image)[rect.top() : rect.bottom() + 1, rect.left() : rect.right() + 1]
    rgb = pixels.astype(int)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    leaf = (g > r + 20) & (g > b + 20)
    text = (rgb.max(axis=2) < 140) & ~leaf
    return rect.top() + np.flatnonzero(leaf.any(axis=1)), rect.top() + np.flatnonzero(
        text.any(axis=1)
    )


def test_each_gallery_name_sits_nearer_its_own_picture_than_the_next_rows(qtbot):
    panel = FormsPanel()
    qtbot.addWidget(panel)
    panel.resize(420, 600)
    panel.show()
    qtbot.waitExposed(panel)
    gallery = panel.gallery
    gallery.setFixedHeight(1200)  # every row in sight
    qtbot.wait(50)
    image = gallery.viewport().grab().toImage()
    items = [gallery.item(i) for i in range(gallery.count())]
    columns: dict[int, list] = {}
    for item in items:
        columns.setdefault(gallery.visualItemRect(item).left(), []).append(item)
    pairs = 0
    for column in columns.values():
        column.sort(key=lambda it: gallery.visualItemRect(it).top())
        for above, below in itertools.pairwise(column):
            if gallery.currentItem() in (above, below):
                continue  # the selection's highlight is not a name's grey
            leaf, text = _gallery_rows(gallery, image, above)
            next_leaf, _ = _gallery_rows(gallery, image, below)
            name = text[text > leaf.max()]
            own, other = name.min() - leaf.max(), next_leaf.min() - name.max()
            assert own < other / 2, (above.text(), below.text(), own, other)
            pairs += 1
    assert pairs >= 4


def test_the_forms_texts_are_words_not_command_line_syntax(qtbot):
    panel = FormsPanel()
    qtbot.addWidget(panel)
    panel.margin.setCurrentText("lobed")
    texts = [label.text() for label in panel.texts.values()]
    texts += [box.toolTip() for box in (panel.teeth, panel.lobes, panel.fold, panel.curl)]
    texts += [box.toolTip() for box in (panel.wave, panel.seed)]
    texts += [panel.margin.itemData(i, Qt.ItemDataRole.ToolTipRole) for i in range(7)]
    for text in texts:
        assert "--" not in text and not re.search(r"\b[A-Z]\b", text.replace("L/W", "")), text


def _failure_over_view(window) -> bool:
    return "message" in window.viewport.plotter.actors


def test_a_refused_files_message_leaves_the_good_leaf_and_a_new_result_clears_the_status(
    window, qtbot, tmp_path
):
    line = tmp_path / "line.csv"  # reads, but cannot be reconstructed: the demo comes back
    line.write_text("\n".join(f"{t},{2 * t},0" for t in np.linspace(0, 1, 20)) + "\n")
    bad = tmp_path / "bad.csv"  # cannot be read
    bad.write_text("x,y,z\n1,2\n")
    with qtbot.waitSignal(window.failure_shown, timeout=30_000):
        window.open_path(str(line))
    window.last_error_box.close()
    assert window.session.result is not None  # the demo's good leaf is on screen ...
    assert not _failure_over_view(window)  # ... without the refused file's message over it
    assert "line.csv" in window.status_text.text()
    with qtbot.waitSignal(window.failure_shown, timeout=30_000):
        window.open_path(str(bad))
    window.last_error_box.close()
    assert "bad.csv" in window.status_text.text()
    with qtbot.waitSignal(window.result_shown, timeout=WAIT_MS):
        window.panel.set_params(replace(window.session.params, k=window.session.params.k + 1))
        window._on_params_released()
    qtbot.waitUntil(lambda: window.worker.is_idle())
    qtbot.wait(100)
    assert "Failed" not in window.status_text.text() and not _failure_over_view(window)
    assert window.status_text.styleSheet() == ""


def test_a_failure_over_the_view_goes_with_the_next_document(window, qtbot):
    window.session.accept_failure(window.session.last_id, ValueError("no such leaf"))
    assert _failure_over_view(window) and "Failed" in window.status_text.text()
    with qtbot.waitSignal(window.result_shown, timeout=WAIT_MS):
        window.open_demo("parallel")
    qtbot.waitUntil(lambda: window.worker.is_idle())
    qtbot.wait(100)
    assert not _failure_over_view(window) and "Failed" not in window.status_text.text()


def _poisson_item(window):
    items = [window.layer_list.item(i) for i in range(window.layer_list.count())]
    return next(it for it in items if it.data(Qt.ItemDataRole.UserRole) == "poisson")


def test_without_open3d_the_poisson_layer_is_disabled_and_names_the_extra(
    qtbot, tmp_path, monkeypatch
):
    monkeypatch.setitem(sys.modules, "open3d", None)  # as if the extra were not installed
    settings = tmp_path / "settings.ini"
    QSettings(str(settings), QSettings.Format.IniFormat).setValue("layers/poisson", True)
    window = make_window(qtbot, settings)
    item = _poisson_item(window)
    assert not item.flags() & Qt.ItemFlag.ItemIsEnabled
    assert item.checkState() == Qt.CheckState.Unchecked  # a saved "on" cannot tick it
    assert "pip install 'leafstudio[open3d]'" in item.toolTip()
    assert not window.viewport.visible["poisson"]


def test_with_open3d_the_poisson_layer_can_be_ticked(qtbot, tmp_path):
    pytest.importorskip("open3d")
    window = make_window(qtbot, tmp_path / "settings.ini")
    item = _poisson_item(window)
    assert item.flags() & Qt.ItemFlag.ItemIsEnabled and "pip install" not in item.toolTip()


def test_ctrl_z_in_a_parameter_field_after_return_undoes_in_the_window(window, qtbot):
    window.activateWindow()
    qtbot.waitUntil(window.isActiveWindow)
    field = window.panel.fields["k"]
    before = window.session.params.k
    field.setFocus()
    field.selectAll()
    qtbot.keyClicks(field, "8")
    with qtbot.waitSignal(window.result_shown, timeout=WAIT_MS):
        qtbot.keyClick(field, Qt.Key.Key_Return)
    assert window.session.params.k == 8 and field.hasFocus()
    qtbot.keyClick(field, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert window.session.params.k == before and field.text() == str(before)
    qtbot.keyClick(
        field, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier
    )
    assert window.session.params.k == 8 and field.text() == "8"
    # while a value is being typed, Ctrl+Z undoes the typing in the field
    qtbot.keyClicks(field, "1")
    qtbot.keyClick(field, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert field.text() == "8" and window.session.params.k == 8


def test_the_first_runs_compile_is_said_in_the_status_while_the_window_responds(
    window, qtbot, monkeypatch
):
    """The first run compiles the kernels in worker processes (core/kernels.py); meanwhile the
    status says so in the CLI's words (issue 24 #5: it said "Running: guide…" for 30 s)."""
    import threading

    from leafstudio._shared.kernelcache import NOTICE
    from leafstudio.core import kernels, pipeline

    compiled = threading.Event()

    def compile_kernels(on_stage=None, workers=None, should_stop=None, tables=()):  # cold: say so
        on_stage(kernels.STAGE)
        on_stage(f"{kernels.STAGE} 1/2")
        compiled.wait(WAIT_MS / 1000)
        return True

    monkeypatch.setattr(pipeline, "compile_kernels", compile_kernels)
    with qtbot.waitSignal(window.result_shown, timeout=WAIT_MS):
        window.panel.set_params(replace(window.session.params, k=window.session.params.k + 1))
        window._on_params_released()
        qtbot.waitUntil(lambda: window.status_text.text() == f"{NOTICE} 1/2")
        clicked = []
        window.docks["Layers"].toggleViewAction().triggered.connect(lambda: clicked.append(1))
        window.docks["Layers"].toggleViewAction().trigger()  # the window still answers
        assert clicked
        compiled.set()
    assert not window.status_text.text().startswith(NOTICE)


def test_measurings_first_compile_is_said_in_the_status_too(window, qtbot, monkeypatch):
    """A cold cache's measuring kernels compile in worker processes once the result is on
    screen (core/kernels.MEASURING), the status saying so; then the result's line is back, and
    its measurements' time is theirs, not the compile's (here a compile of 1000 s)."""
    import threading
    import time

    from leafstudio._shared.kernelcache import NOTICE
    from leafstudio.core import kernels
    from leafstudio.gui.qt import worker

    compiled = threading.Event()
    spent = [0.0]  # the compile's seconds, on the worker's clock

    class Clock:
        """The worker's `time`, its perf_counter past the compile's seconds."""

        def __getattr__(self, name: str):
            return getattr(time, name)

        def perf_counter(self) -> float:
            return time.perf_counter() + spent[0]

    def compile_kernels(on_stage=None, workers=None, should_stop=None, tables=()):
        assert tables == (kernels.MEASURE,)
        on_stage(kernels.STAGE)
        on_stage(f"{kernels.STAGE} 1/6")
        compiled.wait(WAIT_MS / 1000)
        spent[0] += 1000.0
        return {}

    monkeypatch.setattr(worker, "compile_kernels", compile_kernels)
    monkeypatch.setattr(worker, "time", Clock())
    with qtbot.waitSignal(window.result_shown, timeout=WAIT_MS):
        window.panel.set_params(replace(window.session.params, k=window.session.params.k + 1))
        window._on_params_released()
    qtbot.waitUntil(lambda: window.status_text.text() == f"{NOTICE} 1/6", timeout=WAIT_MS)
    with qtbot.waitSignal(window.worker.done, timeout=WAIT_MS):
        compiled.set()
    text = window.status_text.text()
    assert text.startswith(f"K = {window.session.params.k}") and "measured in" in text
    assert float(re.search(r"measured in (\d+) ms", text).group(1)) < 1000 * 1000
