"""The main window: menus, docks (parameters, layers, sketch, measurements), status bar.

The window is chrome around a Session (gui/model/session.py, no Qt): the document, its
parameters, results, undo history, the files being read and the side jobs live there. The
window forwards edits to it, hands it the worker's pipeline reports, and draws what it says. A
failure leaves the last good result on screen and says why; a file that cannot be opened or
reconstructed leaves the current document.

Its menus are built from a table of actions (actions.py; features add rows with
`add_actions`), its docks are added with `add_dock`, the file commands live in
file_commands.py and its answers to the session's and the worker's reports (results drawn,
failures, the status line, measurements) in reports.py.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path

from PySide6.QtCore import QSettings, Qt, Signal
from PySide6.QtGui import QAction, QCloseEvent, QDragEnterEvent, QDropEvent
from PySide6.QtWidgets import QDockWidget, QListWidgetItem, QMainWindow, QMenu, QMessageBox, QWidget

from leafstudio.errors import LeafError
from leafstudio.gui.model.layers import LAYERS
from leafstudio.gui.model.session import Session
from leafstudio.gui.model.textures import LEAF, SHOWS_TEXTURE
from leafstudio.gui.model.view_aids import BladeFollow
from leafstudio.gui.qt import bend_sliders, explain, forms_dock, lesson_view, projector
from leafstudio.gui.qt.actions import MENU_TITLES, WINDOW_ACTIONS, Action
from leafstudio.gui.qt.controls import ParamPanel
from leafstudio.gui.qt.file_commands import ABOUT, APP_NAME, FileCommands
from leafstudio.gui.qt.layers_panel import LayersPanel
from leafstudio.gui.qt.measurements_panel import MeasurementsPanel
from leafstudio.gui.qt.reports import Reports
from leafstudio.gui.qt.sketch import SketchEditor
from leafstudio.gui.qt.status import Busy, NotesButton, StatusText
from leafstudio.gui.qt.viewport import Viewport
from leafstudio.gui.qt.worker import Worker
from leafstudio.model import Params

LEFT, RIGHT = Qt.DockWidgetArea.LeftDockWidgetArea, Qt.DockWidgetArea.RightDockWidgetArea


class MainWindow(FileCommands, Reports, QMainWindow):
    """The app's window. `settings` holds layout, last params and recent files."""

    result_shown = Signal(object)  # Outcome, after it is on screen
    measurements_shown = Signal()  # the panel is complete (with the scan's distances, if any)
    failure_shown = Signal(str)
    texture_shown = Signal()  # a new texture image is on the mesh (the Texture colouring)
    notice_shown = Signal(str)  # a message that is not a failure (a project's photo is missing)
    export_progress = Signal(float, str)  # from the export lane: fraction done, what (exports)

    def __init__(self, settings: QSettings, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.settings = settings
        self.setWindowTitle(APP_NAME)
        self.setAcceptDrops(True)
        self.resize(1500, 920)

        self.last_error_box: QMessageBox | None = None
        self.opened_name = ""  # the file opened last (its name), which a failure may concern
        self._scan_shown: object = None  # the scan whose layer is drawn (scans.ScanData)
        self._coloring_automatic = False  # height set for a scan, not by the user
        self._blade = BladeFollow()  # the laid-flat layer under g, p(x), EM on a bent leaf
        self._blade_ticking = False
        # Kept in Python: walking menuBar().actions() can hand back a stale wrapper of another
        # type (a QSurface) under PySide6, seen intermittently in the GUI tests.
        self.menus: dict[str, QMenu] = {}
        self.actions: dict[str, QAction] = {}
        self.docks: dict[str, QDockWidget] = {}

        self.worker = Worker(self)
        self.worker.measure_after_drawn = True  # measuring would slow the render down
        params = self.saved_params() or Params()
        self.session = Session(
            self.worker.submit_pipeline, params, run=self.worker.start, cancel=self.worker.cancel
        )
        self.viewport = Viewport(self)
        self.viewport.rendered.connect(self._on_rendered)
        self.setCentralWidget(self.viewport)
        self.panel = ParamPanel()
        self.editor = SketchEditor()
        self.layers = LayersPanel(self.viewport.camera)
        self.layer_list, self.edges = self.layers.list, self.layers.edges
        self.coloring = self.layers.coloring
        self.measurements_panel = MeasurementsPanel()  # Copy and Save the table
        self.measurements = self.measurements_panel.tree
        self.status_text = StatusText()  # not a QLabel: see status.py
        self.add_actions(WINDOW_ACTIONS)
        self._build_docks()
        self.statusBar().addWidget(self.status_text, 1)
        self.notes_button = NotesButton(self.status_text)  # how many notes the line has
        self.statusBar().addPermanentWidget(self.notes_button)
        self.busy = Busy()  # a file opening: its progress and Cancel
        self.statusBar().addPermanentWidget(self.busy)
        self.busy.cancelled.connect(self.session.cancel_open)
        self._progress_bar()  # the exports' (exports.py), hidden until one runs

        self.connect_reports()
        self.worker.derives = self.session.derives  # a loaded leaf's sketch, off this thread
        self._connect_session()
        self.panel.changed.connect(self._on_params)
        self.panel.released.connect(self._on_params_released)
        self.panel.released.connect(self._on_rendered)  # measure what the drag left shown
        self.layer_list.itemChanged.connect(self._on_layer_item)
        self.edges.toggled.connect(self.viewport.set_edges)
        self.coloring.currentIndexChanged.connect(self._on_coloring)
        self.forms_panel = forms_dock.install(self)  # the Forms gallery; Grow veins in the editor
        self.bend = bend_sliders.install(self)  # Fold and Curl under K and the grid
        self.view_aids = explain.install(self)  # layer tooltips, exports for slides, view aids
        self.dock_layout = projector.install(self)  # docks as tabs on a narrow window
        self.add_actions(lesson_view.LESSON_ACTIONS)  # View > Lesson, full screen
        self._on_history()
        self._restore_settings()

    def _connect_session(self) -> None:
        session, side = self.session, self.session.side
        session.state_changed.connect(self._on_state)
        session.result_shown.connect(self._on_result)
        session.failed.connect(self._on_session_failed)
        session.cleared.connect(self._on_cleared)
        session.sketch_shown.connect(self.editor.set_sketch)
        session.sketch_waiting.connect(self.editor.wait_for_sketch)  # a loaded leaf: none yet
        session.crossing.connect(self.editor.view.set_crossings)
        session.noticed.connect(self._on_notice)
        session.outline_replaced.connect(self._on_outline_replaced)
        session.history.changed.connect(self._on_history)
        session.opening.connect(self._on_opening)
        self.export_progress.connect(self._on_export_progress)
        session.opened.connect(self._add_recent)
        session.open_failed.connect(self._on_open_failed)
        session.opening.connect(lambda path, _what: self.busy.start(path))
        session.open_progress.connect(self.busy.progress)
        session.open_ended.connect(self.busy.stop)
        session.open_cancelled.connect(lambda: self.status_text.setText("Opening cancelled"))
        side.fidelity_shown.connect(self._show_measurements)
        side.poisson_shown.connect(lambda pieces: self.viewport.set_layer("poisson", pieces))
        side.texture_shown.connect(self._on_texture)
        side.note.connect(self._on_side_note)
        self.editor.preview.connect(session.preview_sketch)
        self.editor.committed.connect(
            lambda before, after, text: session.commit_sketch(after, text, before)
        )
        self.editor.mirror_changed.connect(session.set_symmetric)  # saved with the sketch

    # --- chrome: docks and actions -------------------------------------------------------------
    def add_dock(
        self,
        title: str,
        widget: QWidget,
        area: Qt.DockWidgetArea = LEFT,
        *,
        tab_with: str | None = None,
        listed: bool = False,
    ) -> QDockWidget:
        """Add a dock (`docks[title]`): beside the others in `area`, or a tab of dock
        `tab_with` (which stays in front); `listed`: View can hide and show it. A dock that makes
        a leaf calls session.new_document(leaf, sketch, title=...), one undo step, and the
        window shows it like any other document."""
        dock = QDockWidget(title, self)
        dock.setObjectName(title.lower().replace(" ", "_"))
        dock.setWidget(widget)
        self.addDockWidget(area, dock)
        if tab_with is not None:
            self.tabifyDockWidget(self.docks[tab_with], dock)
            self.docks[tab_with].raise_()
        if listed:
            view = self.menu("View")
            if not any(d.toggleViewAction() in view.actions() for d in self.docks.values()):
                view.addSeparator()
            view.addAction(dock.toggleViewAction())
        self.docks[title] = dock
        return dock

    def menu(self, name: str) -> QMenu:
        """The menu `name` ("File"; actions.MENU_TITLES), made at the end of the bar if new."""
        if name not in self.menus:
            self.menus[name] = self.menuBar().addMenu(MENU_TITLES.get(name, name))
        return self.menus[name]

    def add_actions(self, rows: Iterable[Action]) -> None:
        """Put the table's actions in their menus (`actions[id]`), in order."""
        for row in rows:
            menu = self.menu(row.menu)
            before = self.actions.get(row.before) if row.before else None
            if row.submenu:
                sub = QMenu(row.title, self)
                sub.aboutToShow.connect(lambda r=row, m=sub: r.callback(self, m))
                action = sub.menuAction()
            else:
                action = QAction(row.title, self)
                action.setShortcuts(row.key_sequences())
                action.triggered.connect(lambda _=False, r=row: r.callback(self))
            if row.tip:
                action.setStatusTip(row.tip)
            if row.tooltip:
                action.setToolTip(row.tooltip)
            if row.separator:
                menu.insertSeparator(before) if before is not None else menu.addSeparator()
            menu.insertAction(before, action) if before is not None else menu.addAction(action)
            self.actions[row.id] = action

    def _build_docks(self) -> None:
        self.panel.setMinimumWidth(300)
        # scrolled, not squeezed: a window as short as a projector's (720 px) still fits
        self.add_dock("Parameters", projector.scrolled(self.panel), LEFT, listed=True)
        self.add_dock("Layers", self.layers, LEFT, listed=True)
        self.editor.setMinimumWidth(340)  # with the others, a 1024-px window (projector.py)
        self.add_dock("Sketch", self.editor, RIGHT, listed=True)
        self.measurements_panel.failed.connect(self.show_error)
        measurements = self.add_dock("Measurements", self.measurements_panel, LEFT, listed=True)
        self._measurements_due = False
        measurements.visibilityChanged.connect(
            lambda visible: visible and self._measurements_due and self._show_measurements()
        )
        docks = [self.docks["Parameters"], self.docks["Sketch"]]
        self.resizeDocks(docks, [320, 430], Qt.Orientation.Horizontal)

    # --- settings ------------------------------------------------------------------------------
    def _restore_settings(self) -> None:
        s = self.settings
        if s.value("window/geometry") is not None:
            self.restoreGeometry(s.value("window/geometry"))
        if s.value("window/state") is not None:
            self.restoreState(s.value("window/state"))
        for key, _label, _on in LAYERS:
            on = s.value(f"layers/{key}")
            if on is not None:
                self.layers.set_checked(key, str(on).lower() == "true")
        self.edges.setChecked(str(s.value("view/edges", "false")).lower() == "true")
        self.coloring.setCurrentIndex(max(0, self.coloring.findData(s.value("view/coloring"))))
        self._on_coloring(self.coloring.currentIndex())  # the first choice emits no change
        self.panel.set_params(self.session.params)

    def _on_history(self) -> None:
        """Undo and redo name what they would do, and are off when there is nothing to do."""
        history = self.session.history
        undo, redo = self.actions["edit.undo"], self.actions["edit.redo"]
        undo.setEnabled(history.can_undo())
        undo.setText(f"&Undo {history.undo_text()}".rstrip())
        redo.setEnabled(history.can_redo())
        redo.setText(f"&Redo {history.redo_text()}".rstrip())
        self._update_title()

    def saved_params(self) -> Params | None:
        """The parameters remembered from the last run, if any and valid."""
        text = self.settings.value("params")
        try:
            return Params.from_dict(json.loads(text)) if text else None
        except (LeafError, TypeError, ValueError):
            return None

    def _store_settings(self) -> None:
        s = self.settings
        s.setValue("window/geometry", self.saveGeometry())
        s.setValue("window/state", self.saveState())
        s.setValue("params", json.dumps(self.panel.params().to_dict()))
        for key, on in self.viewport.visible.items():
            s.setValue(f"layers/{key}", on)
        s.setValue("view/edges", self.edges.isChecked())
        picked = LEAF if self._coloring_automatic else self.coloring.currentData()  # not a scan's
        s.setValue("view/coloring", picked)
        s.sync()

    # --- documents -----------------------------------------------------------------------------
    def _update_title(self) -> None:
        state = self.session.state
        name = Path(state.path).name if state.path else state.title
        self.setWindowTitle(f"{name}[*] — {APP_NAME}")
        self.setWindowModified(self.session.is_modified())

    def about(self) -> None:
        """Help > About."""
        QMessageBox.about(self, f"About {APP_NAME}", ABOUT)

    def show_error(self, title: str, message: str) -> None:
        """A window-modal message box that does not block the event loop."""
        box = QMessageBox(
            QMessageBox.Icon.Warning, title, message, QMessageBox.StandardButton.Ok, self
        )
        box.setWindowModality(Qt.WindowModality.WindowModal)
        box.open()
        self.last_error_box = box

    # --- edits ---------------------------------------------------------------------------------
    def _on_params(self, params: Params) -> None:
        self.session.set_params(params, final=not self.panel.is_dragging())

    def _on_params_released(self) -> None:
        self.session.set_params(self.panel.params(), final=True)

    def _on_layer_item(self, item: QListWidgetItem) -> None:
        key = item.data(Qt.ItemDataRole.UserRole)
        on = item.checkState() == Qt.CheckState.Checked
        ticked = on != self.viewport.visible.get(key)  # not a change of flags (set_available)
        self.viewport.set_visible(key, on)
        if key == "poisson":
            self.session.side.set_poisson(self.viewport.visible["poisson"])
        if ticked and not self._blade_ticking:  # not the tick follow_blade gives
            self.follow_blade(key)

    def follow_blade(self, changed: str | None = None) -> None:
        """Tick or untick the "Bent leaf laid flat" layer as the layers drawn on a bent leaf's
        flat blade are shown (view_aids.BladeFollow), after layer `changed` (None: a result)."""
        result = self.session.result
        bent = result is not None and result.leaf.bend is not None
        tick = self._blade.ticked(self.viewport.visible, bent, changed)
        if tick is not None and tick != self.viewport.visible.get("blade"):
            self._blade_ticking = True
            try:
                self.layers.set_checked("blade", tick)
            finally:
                self._blade_ticking = False

    def _on_coloring(self, row: int) -> None:
        """The Layers dock's colouring: a scalar, or the texture (made on the side lane)."""
        self._coloring_automatic = False
        self.viewport.set_mesh_coloring(self.coloring.itemData(row))
        self.session.side.set_texture_shown(self.viewport.mesh_coloring in SHOWS_TEXTURE)

    def _set_coloring(self, coloring: str, automatic: bool) -> None:
        self.coloring.setCurrentIndex(self.coloring.findData(coloring))
        self._coloring_automatic = automatic

    def _on_side_note(self, note: str) -> None:
        """A side job's note: it failed without harm (the Poisson surface, the texture), or the
        scan's distances warn of the surface (scans.fidelity_sections)."""
        self.status_text.add_note(note)

    def _on_texture(self, image: object, key: tuple) -> None:
        self.viewport.set_texture(image, key)
        self.texture_shown.emit()

    def _on_notice(self, message: str) -> None:
        """A message that is not a failure (the leaf is still shown): a box and the status."""
        self.status_text.setStyleSheet("color: #b00020")
        self.status_text.setText(message)
        self.show_error("Note", message)
        self.notice_shown.emit(message)

    # --- window events -------------------------------------------------------------------------
    def dragEnterEvent(self, event: QDragEnterEvent) -> None:
        if any(url.isLocalFile() for url in event.mimeData().urls()):
            event.acceptProposedAction()

    def dropEvent(self, event: QDropEvent) -> None:
        files = [url.toLocalFile() for url in event.mimeData().urls() if url.isLocalFile()]
        if files and self._confirm_discard():
            event.acceptProposedAction()
            self.open_path(files[0])

    def closeEvent(self, event: QCloseEvent) -> None:
        if not self._confirm_discard():
            event.ignore()
            return
        self._store_settings()
        self.worker.shutdown()
        self.close_exports()
        self.viewport.close_plotter()
        event.accept()
