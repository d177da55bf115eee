"""The 3D view as a native child window on X11 (gui/qt/native_view.py).

A QOpenGLWidget makes Qt compose the whole window with OpenGL on every repaint of any widget;
the native view does not. Its pixels come from VTK's frame buffer, so the screenshots must too;
and it owns X connections that must be released while the X server is still there.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PySide6.QtCore import QPoint, QRect
from PySide6.QtGui import QImage
from PySide6.QtOpenGLWidgets import QOpenGLWidget
from PySide6.QtWidgets import QApplication, QFileDialog, QWidget

from leafstudio.gui.qt.native_view import WIDGET_ENV, NativePlotter
from leafstudio.gui.qt.viewport import grab_window
from tests.gui.builders import FAST

from .conftest import close_window, coloured_share, image_pixels, make_window, wait_result

ROOT = Path(__file__).resolve().parents[3]


def _x_sockets() -> int:
    """The process's open sockets (X connections, here)."""
    count = 0
    for fd in os.listdir("/proc/self/fd"):
        with contextlib.suppress(OSError):  # the listing's own descriptor is gone by now
            count += os.readlink(f"/proc/self/fd/{fd}").startswith("socket:")
    return count


NATIVE_TEST = "test_the_3d_view_is_a_native_window_and_nothing_in_the_window_is_drawn_with_gl"


def test_the_3d_view_is_a_native_window_and_nothing_in_the_window_is_drawn_with_gl(window):
    plotter = window.viewport.plotter
    assert isinstance(plotter, NativePlotter)
    assert plotter.internalWinId()  # its own X window, where VTK renders
    assert window.findChildren(QOpenGLWidget) == []
    # only the view and what holds it are native windows, not the docks or the status bar
    chain = [plotter]
    while chain[-1].parentWidget() is not None:
        chain.append(chain[-1].parentWidget())
    native = [w for w in window.findChildren(QWidget) if w.internalWinId()]
    assert native and all(w in chain for w in native)


def test_the_native_view_blits_its_frame_as_colour_only_and_the_screen_shows_it(window, qtbot):
    # the hardware blit's depth pass costs half an empty frame under software OpenGL
    plotter = window.viewport.plotter
    assert plotter.ren_win.GetFrameBlitMode() == plotter.ren_win.BlitToCurrent
    plotter.render()
    qtbot.wait(200)
    viewport = window.viewport
    screen = QApplication.primaryScreen()
    shown = QRect(viewport.mapToGlobal(QPoint(0, 0)), viewport.size()) & screen.geometry()
    on_screen = image_pixels(screen.grabWindow(0, *shown.getRect()).toImage())
    corner = shown.topLeft() - viewport.mapToGlobal(QPoint(0, 0))
    x, y = corner.x(), corner.y()
    drawn = image_pixels(viewport.image())[y : y + shown.height(), x : x + shown.width()]
    # the X server's own pixels (a test display may have 16-bit colour: 8 levels apart)
    assert shown.width() > 100 and shown.height() > 100
    assert np.abs(on_screen.astype(int) - drawn).max() <= 8


def test_the_window_screenshot_and_the_exported_one_show_the_leaf(window, tmp_path, monkeypatch):
    viewport = window.viewport
    shot = grab_window(window, viewport).toImage()
    ratio = shot.devicePixelRatio()
    corner = viewport.mapTo(window, viewport.rect().topLeft())
    x, y = round(corner.x() * ratio), round(corner.y() * ratio)
    w, h = round(viewport.width() * ratio), round(viewport.height() * ratio)
    in_view = image_pixels(shot)[y : y + h, x : x + w]
    share = coloured_share(in_view)
    assert share > 0.03, share

    path = tmp_path / "view.png"
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(path), ""))
    window.export_screenshot_dialog()
    exported = QImage(str(path))
    assert (exported.width(), exported.height()) == (w, h)
    assert coloured_share(image_pixels(exported)) > 0.03


def test_the_opengl_widget_is_the_fallback_and_draws_the_leaf(qtbot, tmp_path, monkeypatch):
    from pyvistaqt import QtInteractor

    monkeypatch.setenv(WIDGET_ENV, "opengl")
    win = make_window(qtbot, tmp_path / "settings.ini", FAST)
    win.open_demo("nested")
    wait_result(qtbot, win)
    assert isinstance(win.viewport.plotter, QtInteractor)
    qtbot.waitUntil(lambda: coloured_share(image_pixels(win.viewport.image())) > 0.03)
    close_window(win)


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="counts the process's sockets")
def test_closing_the_window_releases_the_views_x_connections(qtbot, tmp_path):
    before = _x_sockets()
    win = make_window(qtbot, tmp_path / "settings.ini", FAST)
    win.open_demo("nested")
    wait_result(qtbot, win)
    assert _x_sockets() > before  # VTK's own connections to the X server, while it draws
    close_window(win)
    qtbot.waitUntil(lambda: _x_sockets() == before)


def test_a_gui_test_run_exits_0_although_its_virtual_display_stops_first():
    """pytest-xvfb stops Xvfb at exit, before the interpreter frees what is left: an X
    connection closed after that makes Xlib end the process with status 1."""
    test = f"{Path(__file__).relative_to(ROOT)}::{NATIVE_TEST}"
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", test],
        cwd=ROOT,
        env={**os.environ, "QT_QPA_PLATFORM": "xcb"},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert "XIO" not in done.stderr


def test_dragging_in_the_native_view_turns_the_camera(window, qtbot):
    from PySide6.QtCore import QPoint, Qt
    from PySide6.QtTest import QTest

    plotter = window.viewport.plotter
    before = np.array(plotter.camera.position)
    centre = QPoint(plotter.width() // 2, plotter.height() // 2)
    QTest.mousePress(plotter, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, centre)
    for step in range(1, 11):
        QTest.mouseMove(plotter, centre + QPoint(15 * step, 0))
    QTest.mouseRelease(
        plotter, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, centre + QPoint(150, 0)
    )
    after = np.array(plotter.camera.position)
    assert np.linalg.norm(after - before) > 0.05 * np.linalg.norm(before)


@pytest.mark.parametrize("kind", ["native", "opengl"])
def test_files_dropped_on_the_3d_view_go_to_the_window(kind, qtbot, tmp_path, monkeypatch):
    """The view takes no drops itself (pyvistaqt's would add the file to the scene), so Qt
    hands a file dropped on it to the window, which opens it."""
    monkeypatch.setenv(WIDGET_ENV, kind)
    win = make_window(qtbot, tmp_path / "settings.ini")
    widget = win.viewport.plotter
    while widget is not win:
        assert not widget.acceptDrops(), type(widget).__name__
        widget = widget.parentWidget()
    assert win.acceptDrops()
    close_window(win)
