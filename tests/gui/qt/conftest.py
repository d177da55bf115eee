"""The Qt views' tests: a real main window under Xvfb, with settings in a temporary file (never
the user's)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import shiboken6
from PySide6.QtCore import QSettings
from PySide6.QtGui import QAction, QImage, QPalette
from PySide6.QtWidgets import (
    QAbstractButton,
    QAbstractSlider,
    QAbstractSpinBox,
    QApplication,
    QComboBox,
    QDialog,
    QDoubleSpinBox,
    QLineEdit,
    QListWidget,
    QMessageBox,
    QScrollBar,
    QSpinBox,
    QStackedWidget,
    QTabBar,
    QTabWidget,
    QWidget,
)

from leafstudio.gui.model.textures import LEAF, TEXTURE, texture_key
from leafstudio.gui.qt import turns, worker
from leafstudio.gui.qt.main_window import MainWindow
from leafstudio.gui.qt.photo_dialog import PhotoDialog
from leafstudio.model import Params
from tests.gui.builders import FAST

WAIT_MS = 60_000
APP_LANE_NICENESS = worker.LANE_NICENESS  # the app's, before lanes_at_the_tests_priority


def make_window(qtbot, settings_path, params: Params | None = None) -> MainWindow:
    """A shown window; `params`: the parameters it remembers from a last run (its first)."""
    settings = QSettings(str(settings_path), QSettings.Format.IniFormat)
    if params is not None:
        settings.setValue("params", json.dumps(params.to_dict()))
    window = MainWindow(settings)
    if qtbot is not None:  # None: the caller closes it (LentWindow)
        qtbot.addWidget(window)
    window.show()
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


def settled(qtbot, window: MainWindow) -> None:
    """Wait until the window has nothing left to draw: no job under way, no call waiting for a
    turn (gui/qt/turns.later: a result, a sketch, layers, a render), no render due; then let
    the last render's paint run. A test that counts renders or main-thread pieces starts from
    here: a fixed wait (200 ms) was outlasted by the turns of a busy machine, whose late render
    or layer the test then counted as its own."""
    viewport = window.viewport

    def idle() -> bool:
        return (
            window.worker.is_idle()
            and not turns._queue
            and window._result_due is None
            and window.editor._due is None
            and not viewport._redraw_due
            and not viewport._later
        )

    qtbot.waitUntil(idle, timeout=WAIT_MS)
    QApplication.processEvents()  # the paint that the last turn asked for


def textured(qtbot, window: MainWindow) -> None:
    """Wait until the mesh shows its texture, when its colouring shows one (the Leaf look, a
    new window's): the image is made on the side lane and arrives after the result, so a window
    lent before it came was compared with its fresh self with or without it, by chance, and
    built again for nothing (12 of the 32 windows a run of tests/gui/qt built)."""
    session = window.session
    qtbot.waitUntil(
        lambda: (
            window.viewport.mesh_coloring not in (LEAF, TEXTURE)
            or window.viewport.texture_key == texture_key(session.result, session.texture())
        ),
        timeout=WAIT_MS,
    )


def exported(qtbot, job) -> bool:
    """Wait for an export the window started in the background (gui/qt/exports.py): True once
    it wrote its file, False if it failed or was refused at once (job None)."""
    if job is None:
        return False
    qtbot.waitUntil(lambda: job.finished, timeout=WAIT_MS)
    return job.succeeded


def exports_done(qtbot, window: MainWindow) -> None:
    """Wait until the exports an export dialog started have written their files."""
    qtbot.waitUntil(lambda: window.worker.is_idle("export"), timeout=WAIT_MS)
    qtbot.wait(1)  # their answers, queued to this thread


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


@pytest.fixture(scope="session", autouse=True)
def lanes_at_the_tests_priority():
    """The worker's lanes run at the test process's priority, not LANE_NICENESS nicer. The app
    nices them so that its renders keep the cores while a user waits (issue 24); a test waits
    on the lanes themselves, and beside the other pytest-xdist worker and the host's other load
    a lane 10 nicer got a tenth of a core: test_texture, test_exports, test_compare_glossary and
    test_explain beside one busy process took 129 and 125 s niced, 52 and 44 s not (interleaved,
    load 4.7-5.4), which made the Qt tests' share of the suite follow the host's load (issue 20).
    test_worker checks the app's niceness on a worker of its own (app_niceness)."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(worker, "LANE_NICENESS", 0)
        yield


@pytest.fixture
def app_niceness(monkeypatch) -> int:
    """The app's lane niceness for the workers this test builds (lanes_at_the_tests_priority)."""
    monkeypatch.setattr(worker, "LANE_NICENESS", APP_LANE_NICENESS)
    return APP_LANE_NICENESS


@pytest.fixture(autouse=True)
def never_block_on_questions(monkeypatch):
    """Closing a window with edits would ask a modal question; answer Discard (a test may
    patch another answer)."""
    monkeypatch.setattr(QMessageBox, "question", lambda *a, **k: QMessageBox.StandardButton.Discard)


class LentWindow:
    """The one main window the `window` fixture lends to the tests (building one costs about a
    second): before each test, what the last one changed around the session (boxes, docks,
    toggles, fields) is put back (restore), then the session is reset to what a new window on
    the nested demo shows (an empty sketch, FAST parameters, the demo: a fresh history), unless
    the last test left the session, its jobs and the sketch editor as they were (untouched).
    The window is built again when its chrome still differs from a new one's."""

    def __init__(self, folder) -> None:
        self.folder = folder
        self.window: MainWindow | None = None
        self.made = 0
        self.fresh: tuple[dict, dict] = ({}, {})  # what the window showed when it was new
        self.view: tuple[dict, bool, int] = ({}, False, 0)  # its layers, edges and colouring
        self.controls: tuple = ()  # its controls' settings (restore)
        self.marks: tuple[tuple, tuple] = ((), ())  # its session's, when lent (untouched)

    def lend(self, qtbot) -> MainWindow:
        win = self.window
        # a test that replaced the session's way to the worker and did not give it back (a test
        # that does through monkeypatch, as test_sketch_gap.never_done, keeps the window)
        wired = win is not None and win.session.submit == win.worker.submit_pipeline
        if wired and win.isVisible() and self.restore(win):
            session = win.session
            layers, edges, coloring = self.view  # the view controls a test may have set
            for key, on in layers.items():
                win.layers.set_checked(key, on)
            win.edges.setChecked(edges)
            win.coloring.setCurrentIndex(coloring)
            if self.untouched(win) and chrome(win) == self.fresh[1]:
                assert session_state(win) == self.fresh[0]
                return win  # a test that only looked: nothing to reset
            session.new_sketch()  # File > New sketch: no leaf, nothing to reconstruct
            session.set_params(FAST)
            session.open_demo("nested")
            wait_result(qtbot, win, lambda o: o.request.id == session.last_id)
            textured(qtbot, win)
            # the reset through the session gives what a new window showed
            assert session_state(win) == self.fresh[0]
            if chrome(win) == self.fresh[1]:
                self.marks = marks(win)
                return win
        self.close()
        self.made += 1
        win = make_window(None, self.folder / f"settings{self.made}.ini", FAST)
        win.open_demo("nested")
        wait_result(qtbot, win)
        textured(qtbot, win)
        self.window, self.fresh = win, (session_state(win), chrome(win))
        self.view = dict(win.viewport.visible), win.edges.isChecked(), win.coloring.currentIndex()
        self.controls = controls(win)
        self.marks = marks(win)
        return win

    def untouched(self, win: MainWindow) -> bool:
        """True when the last test changed nothing of the session, its jobs or the sketch
        editor since the window was lent (marks): the reset would give what is there."""
        (same, equal), (same_now, equal_now) = self.marks, marks(win)
        return equal == equal_now and all(a is b for a, b in zip(same, same_now, strict=True))

    def restore(self, win: MainWindow) -> bool:
        """Put back what a test changed around the session, as a user would, rather than build
        the window again (about a second each, 30 times a run): close the boxes it left open,
        free the message boxes and photo dialogs it opened (each use makes a new one), lay the
        docks out again, and turn back its toggles, lists and tabs. What this cannot put back
        (a dialog made once and kept, Help > Compare) still costs a new window. False when a
        control is gone (the window is built again)."""
        try:
            self._restore(win)
        except RuntimeError:  # "Internal C++ object already deleted"
            return False
        return True

    def _restore(self, win: MainWindow) -> None:
        for widget in QApplication.topLevelWidgets():
            if widget.isVisible() and widget is not win:
                widget.close()
        for dialog in win.findChildren(QDialog):
            if isinstance(dialog, ONE_USE) and dialog.isWindow() and not dialog.isVisible():
                shiboken6.delete(dialog)
        win.last_error_box = None
        win.photo_dialog = None
        state, palette, checks, actions, lists, indices, values, texts = self.controls
        win.restoreState(state)
        if win.palette() != palette:  # a test that darkened the window (test_render_cost)
            win.setPalette(palette)
        for on in (True, False):  # an exclusive group's button is checked, not unchecked
            for button, fresh in checks:
                if fresh is on and button.isChecked() is not on:
                    button.click()
        for action, fresh in actions:
            if action.isChecked() is not fresh:
                action.trigger()
        for item, fresh in lists:
            item.setCheckState(fresh)
        for widget, fresh in indices:
            widget.setCurrentIndex(fresh)
        for widget, fresh in values:
            widget.setValue(fresh)
        for widget, fresh in texts:
            widget.setText(fresh)

    def close(self) -> None:
        if self.window is not None:
            close_window(self.window)
            self.window.worker.join(WAIT_MS / 1000)  # no job outlives the window's tests
            self.window.deleteLater()
            self.window = None


def session_state(window: MainWindow) -> dict:
    """What a new window on the nested demo shows of its session: the document, parameters,
    history and result."""
    session, outcome = window.session, window.session.shown.outcome
    return {
        "document": (session.state.title, session.state.path, session.state.scan),
        "photo": (session.state.photo, session.texture()),
        "params": session.params,
        "history": (session.history.can_undo(), session.history.can_redo(), session.is_modified()),
        "result": (outcome.request.id == session.last_id, outcome.result.leaf is session.leaf),
        "mesh": outcome.result.mesh.n_points,
        "message": session.message,
        "title": (window.windowTitle(), window.isWindowModified()),
    }


def chrome(window: MainWindow) -> dict:
    """What a test may change around the session: toggles, lists, combo boxes, docks, the 3D
    view's layers and camera, the window's size and the boxes open over it."""
    widgets = window.findChildren(QWidget)
    plotter = window.viewport.plotter
    return {
        # by widget, not in the order Qt lists them (moving a dock moves its toggle in it)
        "checks": {b: b.isChecked() for b in window.findChildren(QAbstractButton)},
        "actions": {a: a.isChecked() for a in window.findChildren(QAction)},
        "lists": {
            w: [w.item(i).checkState() for i in range(w.count())]
            for w in window.findChildren(QListWidget)
        },
        "indices": {w: w.currentIndex() for w in widgets if isinstance(w, INDEXED)},
        "values": {w: w.value() for w in widgets if valued(w)},
        "texts": {w: w.text() for w in widgets if isinstance(w, QLineEdit)},
        "docks": [(d.isVisible(), d.isFloating()) for d in window.docks.values()],
        "widgets": len(widgets),
        "layers": dict(window.viewport.visible),
        "view": (
            window.viewport.texture_key,
            window.viewport.show_edges,
            window.viewport.mesh_coloring,
        ),
        "actors": sorted(name for name in plotter.actors if not name.startswith("vtk")),
        "unnamed": sum(name.startswith("vtk") for name in plotter.actors),  # named by address
        "bars": sorted(plotter.scalar_bars.keys()),
        "camera": np.round(plotter.camera_position.to_list(), 6).tolist(),
        "size": (window.width(), window.height()),
        "palette": window.palette().color(QPalette.ColorRole.Base).name(),
        "boxes": [w for w in QApplication.topLevelWidgets() if w.isVisible() and w is not window],
        "error_box": window.last_error_box,
    }


INDEXED = (QComboBox, QTabBar, QTabWidget, QStackedWidget)
VALUED = (QSpinBox, QDoubleSpinBox, QAbstractSlider)
ONE_USE = (QMessageBox, PhotoDialog)  # made anew each time they are shown


def marks(window: MainWindow) -> tuple[tuple, tuple]:
    """What any work with the session, its jobs or the sketch editor changes: the objects it
    replaces (compared by identity) and the values it sets (LentWindow.untouched)."""
    session, history, view = window.session, window.session.history, window.editor.view
    same = (session.state, session.shown.outcome, session.derived, view.sketch, *history.steps)
    equal = (
        (session.last_id, window.worker.last_id, session.message),  # a job a test started
        (len(history.steps), history.index, history.clean_index, session.chosen_texture),
        (window.panel.params() == session.params, view.transform()),
        (view.active, view.selected, view.select_tool),
    )
    return same, equal


def controls(window: MainWindow) -> tuple:
    """The window's dock layout and its controls with their settings (LentWindow.restore)."""
    lists, widgets = window.findChildren(QListWidget), window.findChildren(QWidget)
    return (
        window.saveState(),
        QPalette(window.palette()),
        [(b, b.isChecked()) for b in window.findChildren(QAbstractButton) if b.isCheckable()],
        [(a, a.isChecked()) for a in window.findChildren(QAction) if a.isCheckable()],
        [(w.item(i), w.item(i).checkState()) for w in lists for i in range(w.count())],
        [(w, w.currentIndex()) for w in widgets if isinstance(w, INDEXED)],
        [(w, w.value()) for w in widgets if valued(w)],
        [(w, w.text()) for w in widgets if typed(w)],
    )


def valued(widget: QWidget) -> bool:
    """A spin box or slider (a scroll bar's value follows what its view holds)."""
    return isinstance(widget, VALUED) and not isinstance(widget, QScrollBar)


def typed(widget: QWidget) -> bool:
    """A line edit of its own (a spin box's is its value)."""
    return isinstance(widget, QLineEdit) and not isinstance(widget.parent(), QAbstractSpinBox)


@pytest.fixture(scope="session")
def lent_window(qapp, tmp_path_factory):
    lent = LentWindow(tmp_path_factory.mktemp("window"))
    yield lent
    lent.close()


@pytest.fixture
def window(lent_window, qtbot):
    """The main window on the nested demo at a small grid, with its first result shown: one
    window for the whole run (LentWindow), reset to that before each test."""
    return lent_window.lend(qtbot)
