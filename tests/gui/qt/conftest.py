"""The Qt views' tests: a real main window under Xvfb, with settings in a temporary file (never
the user's)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PySide6.QtCore import QSettings
from PySide6.QtGui import QImage
from PySide6.QtWidgets import QMessageBox

from leafstudio.gui.qt.main_window import MainWindow
from leafstudio.model import Params
from tests.gui.builders import FAST

WAIT_MS = 60_000


def make_window(qtbot, settings_path, params: Params | None = None) -> MainWindow:
    """A shown window; `params`: the parameters it remembers from a last run (its first)."""
    settings = QSettings(str(settings_path), QSettings.Format.IniFormat)
    if params is not None:
        settings.setValue("params", json.dumps(params.to_dict()))
    window = MainWindow(settings)
    qtbot.addWidget(window)
    window.show()
    qtbot.waitExposed(window)
    return window


def wait_result(qtbot, window: MainWindow, check=lambda outcome: True) -> object:
    """Wait until the worker is idle and the shown outcome passes `check`; return it."""
    qtbot.waitUntil(
        lambda: (
            window.session.shown.outcome is not None
            and window.worker.is_idle()
            and check(window.session.shown.outcome)
        ),
        timeout=WAIT_MS,
    )
    return window.session.shown.outcome


def image_pixels(image: QImage) -> np.ndarray:
    """An image's (h, w, 3) RGB pixels, copied out of Qt's buffer."""
    image = image.convertToFormat(QImage.Format.Format_RGB888)
    rows = np.frombuffer(image.constBits(), np.uint8, image.sizeInBytes())
    rows = rows.reshape(image.height(), image.bytesPerLine())
    return rows[:, : 3 * image.width()].reshape(image.height(), image.width(), 3).copy()


def coloured_share(pixels: np.ndarray) -> float:
    """Share of strongly coloured pixels: the height colour map on the leaf (viridis), never
    the grey background, the widgets, or a black unread frame."""
    rgb = pixels.astype(float)
    spread = rgb.max(axis=2) - rgb.min(axis=2)
    return float(np.mean(spread > 60))


def close_window(window: MainWindow) -> None:
    window.session.history.set_clean()
    window.close()


@pytest.fixture(autouse=True)
def never_block_on_questions(monkeypatch):
    """Closing a window with edits would ask a modal question; answer Discard (a test may
    patch another answer)."""
    monkeypatch.setattr(QMessageBox, "question", lambda *a, **k: QMessageBox.StandardButton.Discard)


@pytest.fixture
def window(qtbot, tmp_path):
    """The main window on the nested demo at a small grid, with its first result shown."""
    win = make_window(qtbot, tmp_path / "settings.ini", FAST)
    win.open_demo("nested")
    wait_result(qtbot, win)
    yield win
    close_window(win)
