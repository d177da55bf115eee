"""Findings of a teacher's and a new user's first hour (issues 22 and 24): the first-start
layout, the gallery's names and words, stale failures, the Poisson layer without open3d, and
undo from a parameter field."""

from __future__ import annotations

from PySide6.QtCore import QSettings

from tests.gui.qt.conftest import close_window, make_window


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
