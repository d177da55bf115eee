"""The main window: menus, docks (parameters, layers, sketch, measurements), status bar, undo.

The document is a Leaf, possibly drawn by a Sketch, plus Params. Every edit asks the worker for a
new Result; results and failures come back by signal. A failure leaves the last good result on
screen and says why; a file that cannot be opened or reconstructed leaves the current document.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path

from PySide6.QtCore import QSettings, Qt, QTimer, Signal
from PySide6.QtGui import (
    QAction,
    QCloseEvent,
    QDragEnterEvent,
    QDropEvent,
    QKeySequence,
    QUndoCommand,
    QUndoStack,
)
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDockWidget,
    QFileDialog,
    QHBoxLayout,
    QLabel,
    QListWidget,
    QListWidgetItem,
    QMainWindow,
    QMessageBox,
    QPushButton,
    QTreeWidget,
    QTreeWidgetItem,
    QVBoxLayout,
    QWidget,
)

from leafstudio.demos import DEMOS, PAPER_K, demo
from leafstudio.errors import LeafError
from leafstudio.gui.controls import ParamPanel
from leafstudio.gui.layers import LAYERS, MESH_COLORINGS
from leafstudio.gui.measurements import measurement_rows
from leafstudio.gui.scans import (
    ScanData,
    fidelity_sections,
    is_scan_file,
    load_scan,
    looks_like_scan,
    poisson_piece,
)
from leafstudio.gui.sketch import SketchEditor
from leafstudio.gui.sketch_model import Sketch
from leafstudio.gui.tasks import TaskWorker
from leafstudio.gui.viewport import CAMERAS, Viewport
from leafstudio.gui.worker import Outcome, PipelineWorker
from leafstudio.io import (
    LEAF_SUFFIXES,
    MESH_SUFFIXES,
    load_leaf,
    load_project,
    save_leaf,
    save_mesh,
)
from leafstudio.model import Leaf, Params
from leafstudio.scan import SCAN_SUFFIXES

APP_NAME = "LeafStudio"
PROJECT_SUFFIX = ".leaf.json"
MAX_RECENT = 8
STAGE_LABEL_MS = 250  # the running stage is shown at most this often (each repaint costs time)
ABOUT = (
    "<h3>LeafStudio</h3>"
    "<p>Smooth 3D leaf surfaces from a leaf's boundary and vein points.</p>"
    "<p>An implementation of Nagai &amp; Tanaya, <i>Leaf Reconstruction Based on Gaussian Mixture "
    "Model from Point Clouds of Leaf Boundaries and Veins</i>: a PCA plane, a 2D multi-level "
    "partition-of-unity implicit for the leaf region, a height guide from the veins, a Gaussian "
    "mixture fitted by EM, and a mesh trimmed at the margin.</p>"
)


@dataclass(frozen=True, eq=False)
class Doc:
    """What is being edited: a leaf (None while a sketch has too few points) and its sketch
    (None for a leaf read from points, until it is first edited)."""

    leaf: Leaf | None
    sketch: Sketch | None = None


class DocCommand(QUndoCommand):
    """One undoable edit: swaps the window's document between two snapshots."""

    def __init__(self, window: MainWindow, before: Doc, after: Doc, text: str) -> None:
        super().__init__(text)
        self._window, self._before, self._after = window, before, after

    def redo(self) -> None:
        self._window.apply_doc(self._after)

    def undo(self) -> None:
        self._window.apply_doc(self._before)


def _file_filter() -> str:
    patterns = " ".join(f"*{s}" for s in LEAF_SUFFIXES)
    return f"Leaves ({patterns});;{_scan_filter()}"


def _scan_filter() -> str:
    patterns = " ".join(f"*{s}" for s in SCAN_SUFFIXES)
    return f"Leaf scans ({patterns});;All files (*)"


class MainWindow(QMainWindow):
    """The app's window. `settings` holds layout, last params and recent files."""

    result_shown = Signal(object)  # Outcome, after it is on screen
    measurements_shown = Signal()  # the panel is complete (with the scan's distances, if any)
    failure_shown = Signal(str)

    def __init__(self, settings: QSettings, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.settings = settings
        self.setWindowTitle(APP_NAME)
        self.setAcceptDrops(True)
        self.resize(1500, 920)

        self.doc = Doc(None)
        self.path: str | None = None
        self.result = None  # the last good Result
        self.outcome: Outcome | None = None
        self.last_error_box: QMessageBox | None = None
        self._shown_id = 0
        self._saved_params: Params | None = None
        self._edit_base: Doc | None = None
        self._derived: tuple[Leaf, Sketch] | None = None
        self._fallback: tuple[Doc, str | None, Params, int] | None = None
        self._fit_sketch = False
        self._title = APP_NAME
        self.scan: ScanData | None = None  # the open scan, whose leaf is being edited
        self._fallback_scan: ScanData | None = None
        self._scan_due: str | None = None  # the scan being read; another open supersedes it
        self.fidelity: tuple[int, list] | None = None  # request id, the panel's scan sections
        self._measured_id = 0
        self._poisson_leaf: Leaf | None = None  # the leaf of the Poisson surface drawn or due

        self.undo_stack = QUndoStack(self)
        self.worker = PipelineWorker(self)
        self.tasks = TaskWorker(self)
        self.viewport = Viewport(self)
        self.setCentralWidget(self.viewport)
        self.panel = ParamPanel()
        self.editor = SketchEditor()
        self.layer_list, self.edges = QListWidget(), QCheckBox("Show mesh edges")
        self.measurements = QTreeWidget()
        self.status_text = QLabel("")
        self._build_docks()
        self._build_menus()
        self.statusBar().addWidget(self.status_text, 1)

        self.worker.stage_started.connect(self._on_stage)
        self.worker.finished.connect(self._on_finished)
        self.worker.measured.connect(self._on_measured)
        self._stage_timer = QTimer(self)
        self._stage_timer.setSingleShot(True)
        self._stage_timer.setInterval(STAGE_LABEL_MS)
        self._stage_timer.timeout.connect(self._show_stage)
        self._stage = ""
        self.worker.failed.connect(self._on_failed)
        self.tasks.done.connect(self._on_task_done)
        self.tasks.failed.connect(self._on_task_failed)
        self.panel.changed.connect(self._on_params)
        self.editor.preview.connect(self._on_sketch_preview)
        self.editor.committed.connect(self._on_sketch_committed)
        self.undo_stack.cleanChanged.connect(lambda _: self._update_title())
        self._restore_settings()

    # --- layout --------------------------------------------------------------------------------
    def _dock(self, title: str, widget: QWidget, area: Qt.DockWidgetArea) -> QDockWidget:
        dock = QDockWidget(title, self)
        dock.setObjectName(title.lower().replace(" ", "_"))
        dock.setWidget(widget)
        self.addDockWidget(area, dock)
        return dock

    def _build_docks(self) -> None:
        left, right = Qt.DockWidgetArea.LeftDockWidgetArea, Qt.DockWidgetArea.RightDockWidgetArea
        self.panel.setMinimumWidth(300)
        self.params_dock = self._dock("Parameters", self.panel, left)

        for key, label, on in LAYERS:
            item = QListWidgetItem(label)
            item.setData(Qt.ItemDataRole.UserRole, key)
            item.setFlags(item.flags() | Qt.ItemFlag.ItemIsUserCheckable)
            item.setCheckState(Qt.CheckState.Checked if on else Qt.CheckState.Unchecked)
            self.layer_list.addItem(item)
        self.layer_list.itemChanged.connect(self._on_layer_item)
        self.layer_list.setMaximumHeight(self.layer_list.sizeHintForRow(0) * len(LAYERS) + 8)
        self.edges.setToolTip("Draw the triangles' edges on the mesh.")
        self.edges.toggled.connect(self.viewport.set_edges)
        self.coloring = QComboBox()
        for name, (label, _) in MESH_COLORINGS.items():
            self.coloring.addItem(f"Colour by {label}", name)
        self.coloring.setToolTip(
            "What the mesh's colours show: its height above the leaf's plane, or how it bends "
            "(mean or Gaussian curvature; red bends one way, blue the other)."
        )
        self.coloring.currentIndexChanged.connect(
            lambda row: self.viewport.set_mesh_coloring(self.coloring.itemData(row))
        )
        cameras = QHBoxLayout()
        for preset in CAMERAS:
            button = QPushButton(preset.capitalize())
            button.setToolTip(f"Look at the leaf from the {preset} view.")
            button.clicked.connect(lambda _=False, p=preset: self.viewport.camera(p))
            cameras.addWidget(button)
        layers = QWidget()
        column = QVBoxLayout(layers)
        column.addWidget(self.layer_list)
        column.addWidget(self.edges)
        column.addWidget(self.coloring)
        column.addLayout(cameras)
        column.addStretch(1)
        self.layers_dock = self._dock("Layers", layers, left)

        self.editor.setMinimumWidth(380)
        self.sketch_dock = self._dock("Sketch", self.editor, right)
        self.measurements.setHeaderLabels(["Measure", "Value"])
        self.measurements.setColumnWidth(0, 190)
        self.measurements_dock = self._dock("Measurements", self.measurements, left)
        self.resizeDocks(
            [self.params_dock, self.sketch_dock], [320, 430], Qt.Orientation.Horizontal
        )

    def _action(self, menu, text: str, slot, shortcut=None, tip: str = "") -> QAction:
        action = QAction(text, self)
        if shortcut is not None:
            action.setShortcut(QKeySequence(shortcut))
        if tip:
            action.setStatusTip(tip)
        action.triggered.connect(slot)
        menu.addAction(action)
        return action

    def _build_menus(self) -> None:
        bar = self.menuBar()
        files = bar.addMenu("&File")
        keys = QKeySequence.StandardKey
        self._action(files, "&New sketch", self.new_sketch, keys.New, "Draw a new leaf")
        self._action(files, "&Open…", self.open_dialog, keys.Open, "Open a leaf, project or scan")
        self._action(
            files,
            "Open s&can…",
            self.open_scan_dialog,
            "Ctrl+Shift+O",
            "Open a 3D scan of a leaf: its boundary and veins are extracted and can be edited",
        )
        self.recent_menu = files.addMenu("Open &recent")
        self.recent_menu.aboutToShow.connect(self._fill_recent)
        files.addSeparator()
        self._action(files, "&Save", self.save, keys.Save, "Save the project (.leaf.json)")
        self._action(files, "Save &as…", self.save_as, keys.SaveAs)
        self._action(
            files,
            "&Export mesh…",
            self.export_mesh_dialog,
            "Ctrl+E",
            "Write the mesh as .ply, .obj, .stl, .vtp or .vtk",
        )
        self._action(files, "Export &screenshot…", self.export_screenshot_dialog, "Ctrl+Shift+E")
        files.addSeparator()
        self._action(files, "&Quit", self.close, keys.Quit)

        edit = bar.addMenu("&Edit")
        self.undo_action = self.undo_stack.createUndoAction(self, "&Undo")
        self.undo_action.setShortcut(QKeySequence(keys.Undo))
        self.redo_action = self.undo_stack.createRedoAction(self, "&Redo")
        self.redo_action.setShortcut(QKeySequence(keys.Redo))
        edit.addActions([self.undo_action, self.redo_action])

        view = bar.addMenu("&View")
        for i, preset in enumerate(CAMERAS, start=1):
            self._action(
                view,
                f"{preset.capitalize()} view",
                lambda _=False, p=preset: self.viewport.camera(p),
                f"Ctrl+{i}",
            )
        view.addSeparator()
        for dock in (self.params_dock, self.layers_dock, self.sketch_dock, self.measurements_dock):
            view.addAction(dock.toggleViewAction())

        demos = bar.addMenu("&Demos")
        for name in DEMOS:
            self._action(
                demos,
                f"{name.capitalize()} veins",
                lambda _=False, n=name: self.open_demo(n),
                tip=f"The paper's {name} leaf",
            )

        about = bar.addMenu("&Help")
        self._action(about, "&About LeafStudio", self.about)

    # --- settings ------------------------------------------------------------------------------
    def _restore_settings(self) -> None:
        s = self.settings
        if s.value("window/geometry") is not None:
            self.restoreGeometry(s.value("window/geometry"))
        if s.value("window/state") is not None:
            self.restoreState(s.value("window/state"))
        for row in range(self.layer_list.count()):
            item = self.layer_list.item(row)
            key = item.data(Qt.ItemDataRole.UserRole)
            on = s.value(f"layers/{key}")
            if on is not None:
                item.setCheckState(
                    Qt.CheckState.Checked if str(on).lower() == "true" else Qt.CheckState.Unchecked
                )
        self.edges.setChecked(str(s.value("view/edges", "false")).lower() == "true")
        self.coloring.setCurrentIndex(max(0, self.coloring.findData(s.value("view/coloring"))))
        self.panel.set_params(self.saved_params() or Params())

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
        s.setValue("view/coloring", self.coloring.currentData())
        s.sync()

    def recent_files(self) -> list[str]:
        """Recently opened or saved files, newest first."""
        value = self.settings.value("recent") or []
        return [value] if isinstance(value, str) else list(value)

    def _add_recent(self, path: str) -> None:
        path = str(Path(path).resolve())
        recent = [path] + [p for p in self.recent_files() if p != path]
        self.settings.setValue("recent", recent[:MAX_RECENT])

    def _fill_recent(self) -> None:
        self.recent_menu.clear()
        for path in self.recent_files():
            action = self.recent_menu.addAction(path)
            action.triggered.connect(
                lambda _=False, p=path: self._confirm_discard() and self.open_path(p)
            )
        self.recent_menu.setEnabled(bool(self.recent_files()))

    # --- documents -----------------------------------------------------------------------------
    def is_modified(self) -> bool:
        """True when there are edits not saved: sketch edits, or params of a saved project."""
        if not self.undo_stack.isClean():
            return True
        return self.path is not None and self.panel.params() != self._saved_params

    def _update_title(self) -> None:
        name = Path(self.path).name if self.path else self._title
        self.setWindowTitle(f"{name}[*] — {APP_NAME}")
        self.setWindowModified(self.is_modified())

    def _confirm_discard(self) -> bool:
        """Ask what to do with unsaved changes; True when it is fine to go on."""
        if not self.is_modified():
            return True
        answer = QMessageBox.question(
            self,
            APP_NAME,
            "The leaf has unsaved changes. Save them first?",
            QMessageBox.StandardButton.Save
            | QMessageBox.StandardButton.Discard
            | QMessageBox.StandardButton.Cancel,
        )
        if answer == QMessageBox.StandardButton.Save:
            return self.save()
        return answer == QMessageBox.StandardButton.Discard

    def _switch(
        self,
        doc: Doc,
        path: str | None,
        title: str,
        params: Params | None,
        scan: ScanData | None = None,
    ) -> None:
        """Make `doc` (extracted from `scan`, if given) the document, keeping the current one to
        fall back to if it fails."""
        self._fallback, self._scan_due = None, None
        if doc.leaf is not None and self.doc.leaf is not None and self.result is not None:
            self._fallback = (self.doc, self.path, self.panel.params(), 0)
            self._fallback_scan = self.scan
        self._set_scan(scan)
        self.doc, self.path, self._title = doc, path, title
        self._derived, self._edit_base = None, None
        if params is not None:
            self.panel.set_params(params)
        self._saved_params = self.panel.params()
        self._fit_sketch = True
        self.editor.set_sketch(doc.sketch or Sketch(), fit=doc.sketch is not None)
        request = self._request()
        if self._fallback is not None:
            self._fallback = (*self._fallback[:3], request)
        self.undo_stack.clear()
        self._update_title()

    def open_demo(self, name: str) -> None:
        """Open a built-in leaf with the paper's K."""
        if self._confirm_discard():
            params = self.panel.params().with_(k=PAPER_K.get(name, self.panel.params().k))
            self._switch(Doc(demo(name)), None, f"{name} demo", params)

    def open_path(self, path: str) -> bool:
        """Open a leaf file or project; on failure show why and keep the current leaf."""
        try:
            params, sketch = None, None
            if path.lower().endswith(".json"):
                leaf, params, stored = load_project(path)
                try:
                    sketch = Sketch.from_dict(stored) if stored else None
                except (TypeError, ValueError, KeyError) as exc:
                    raise LeafError(f"bad sketch ({exc})", path) from None
            else:
                try:
                    leaf = load_leaf(path)
                except LeafError:
                    if is_scan_file(path):
                        return self.open_scan(path)
                    raise
                if looks_like_scan(leaf):
                    return self.open_scan(path)
        except LeafError as exc:
            self.show_error("Cannot open the file", str(exc))
            return False
        except OSError as exc:
            self.show_error("Cannot open the file", f"{path}: {exc.strerror or exc}")
            return False
        self._switch(Doc(leaf, sketch), path, Path(path).name, params)
        self._add_recent(path)
        return True

    def open_dialog(self) -> None:
        """File > Open."""
        path = self._ask_to_open("Open a leaf", _file_filter())
        if path:
            self.open_path(path)

    def open_scan(self, path: str) -> bool:
        """Read a scan and extract its leaf off the main thread; the leaf then opens like any
        loaded leaf (editable as a sketch), with the scan's points as a layer. Failures show a
        message and keep the current leaf. True: the scan is being read."""
        self.status_text.setStyleSheet("")
        self.status_text.setText(f"Reading the scan {Path(path).name} and extracting its leaf…")
        self._scan_due = path
        self.tasks.submit("scan", path, load_scan, path)
        return True

    def open_scan_dialog(self) -> None:
        """File > Open scan."""
        path = self._ask_to_open("Open a leaf scan", _scan_filter())
        if path:
            self.open_scan(path)

    def _ask_to_open(self, title: str, filters: str) -> str:
        """A file chosen in an open dialog beside the current file, once unsaved changes are
        dealt with; "" when cancelled."""
        if not self._confirm_discard():
            return ""
        start = str(Path(self.path).parent) if self.path else str(Path.home())
        return QFileDialog.getOpenFileName(self, title, start, filters)[0]

    def _set_scan(self, scan: ScanData | None) -> None:
        self.scan, self.fidelity = scan, None
        self.viewport.set_layer("scan", scan.pieces if scan is not None else [])

    def new_sketch(self) -> None:
        """File > New sketch: an empty sketch to draw a leaf in."""
        if not self._confirm_discard():
            return
        self._switch(Doc(None, Sketch()), None, "new sketch", None)
        self.editor.set_sketch(Sketch(), fit=True)
        self.sketch_dock.show()
        self.sketch_dock.raise_()

    def save(self) -> bool:
        """File > Save: write the project; Save as when it has no project file yet."""
        if self.path is None or not self.path.lower().endswith(PROJECT_SUFFIX):
            return self.save_as()
        return self.save_to(self.path)

    def save_as(self) -> bool:
        """File > Save as."""
        start = self.path or str(Path.home() / f"leaf{PROJECT_SUFFIX}")
        if not start.lower().endswith(PROJECT_SUFFIX):
            start = str(Path(start).with_suffix("")) + PROJECT_SUFFIX
        path, _ = QFileDialog.getSaveFileName(
            self, "Save the project", start, f"LeafStudio projects (*{PROJECT_SUFFIX})"
        )
        if not path:
            return False
        if not path.lower().endswith(PROJECT_SUFFIX):
            path += PROJECT_SUFFIX
        return self.save_to(path)

    def save_to(self, path: str) -> bool:
        """Write the project (leaf, params, sketch) to `path` atomically."""
        if self.doc.leaf is None:
            self.show_error("Nothing to save", "The sketch needs at least 3 boundary points.")
            return False
        params = self.panel.params()
        sketch = self.doc.sketch.to_dict() if self.doc.sketch is not None else None
        try:
            save_leaf(self.doc.leaf, path, params, sketch)
        except (LeafError, OSError) as exc:
            self.show_error("Cannot save", str(exc))
            return False
        self.path, self._saved_params = path, params
        self.undo_stack.setClean()
        self._add_recent(path)
        self._update_title()
        return True

    def export_mesh(self, path: str) -> bool:
        """Write the shown mesh to `path` (.ply, .obj, .stl, .vtp or .vtk)."""
        if self.result is None:
            self.show_error("Nothing to export", "There is no reconstructed mesh yet.")
            return False
        try:
            save_mesh(self.result, path)
        except (LeafError, OSError) as exc:
            self.show_error("Cannot export the mesh", str(exc))
            return False
        return True

    def export_mesh_dialog(self) -> None:
        """File > Export mesh."""
        patterns = " ".join(f"*{s}" for s in MESH_SUFFIXES)
        path, _ = QFileDialog.getSaveFileName(self, "Export the mesh", "", f"Meshes ({patterns})")
        if path:
            self.export_mesh(path if Path(path).suffix else path + ".ply")

    def export_screenshot_dialog(self) -> None:
        """File > Export screenshot: the 3D view as PNG."""
        path, _ = QFileDialog.getSaveFileName(self, "Export a screenshot", "", "PNG (*.png)")
        if path:
            path = path if path.lower().endswith(".png") else path + ".png"
            if not self.viewport.plotter.interactor.grab().save(path):
                self.show_error("Cannot save the screenshot", f"{path}: not written")

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
    def apply_doc(self, doc: Doc) -> None:
        """Show `doc` (from an undo command) and reconstruct it unless it is already current."""
        current = doc is self.doc
        self.doc = doc
        shown = doc.sketch
        if shown is None and self._derived is not None and self._derived[0] is doc.leaf:
            shown = self._derived[1]
        if shown is not None and shown is not self.editor.view.sketch:
            self.editor.set_sketch(shown)
        if not current:
            self._request()
        self._update_title()

    def _on_sketch_preview(self, sketch: Sketch) -> None:
        if self._edit_base is None:
            self._edit_base = self.doc
        self.doc = Doc(sketch.to_leaf(), sketch)
        self._request(interrupt=False)

    def _on_sketch_committed(self, before: Sketch, after: Sketch, text: str) -> None:
        base = self._edit_base or self.doc
        self._edit_base = None
        doc = self.doc if self.doc.sketch is after else Doc(after.to_leaf(), after)
        self.undo_stack.push(DocCommand(self, base, doc, text))

    def _on_params(self, params: Params) -> None:
        self._request()
        self._update_title()

    def _on_layer_item(self, item: QListWidgetItem) -> None:
        key = item.data(Qt.ItemDataRole.UserRole)
        self.viewport.set_visible(key, item.checkState() == Qt.CheckState.Checked)
        if key == "poisson":
            self._update_poisson()

    def _update_poisson(self) -> None:
        """Compute the Poisson surface of the shown leaf when its layer is on and it is not
        there yet; when the layer is off, forget a surface that no longer fits the leaf."""
        leaf = self.result.leaf if self.result is not None else None
        if leaf is self._poisson_leaf:
            return
        if self.viewport.visible["poisson"] and self.result is not None:
            self._poisson_leaf = leaf
            self.tasks.submit("poisson", leaf, poisson_piece, self.result)
        else:
            self._poisson_leaf = None
            self.viewport.set_layer("poisson", [])

    def _request(self, interrupt: bool = True) -> int:
        if self.doc.leaf is None:
            self.viewport.clear()
            if self.scan is not None:
                self.viewport.set_layer("scan", self.scan.pieces)
            self.measurements.clear()
            self.result = None
            self.status_text.setText("Add at least 3 boundary points to see the leaf.")
            return 0
        return self.worker.submit(self.doc.leaf, self.panel.params(), interrupt)

    # --- worker reports ------------------------------------------------------------------------
    def _on_stage(self, request_id: int, stage: str) -> None:
        if request_id == self.worker.last_id:
            self._stage = stage
            if not self._stage_timer.isActive():
                self._stage_timer.start()

    def _show_stage(self) -> None:
        if not self.worker.is_idle():
            self.status_text.setStyleSheet("")
            self.status_text.setText(f"Running: {self._stage}…")

    def _on_measured(self, request_id: int, seconds: float) -> None:
        if request_id != self._shown_id or self.result is None:
            return
        self._measured_id = request_id
        self.status_text.setText(
            self.status_text.text() + f" · measurements {1000 * seconds:.0f} ms"
        )
        self._show_measurements()

    def _on_finished(self, outcome: Outcome) -> None:
        if outcome.request.id < self._shown_id:
            return
        self._shown_id = outcome.request.id
        result = outcome.result
        start = time.perf_counter()
        self.viewport.show_layers(outcome.layers, result.frame.normal, result.frame.u)
        outcome.timings["draw"] = time.perf_counter() - start
        self.result, self.outcome = result, outcome
        if self._fallback is not None and outcome.request.id >= self._fallback[3]:
            self._fallback = None
        if self.doc.sketch is None and result.leaf is self.doc.leaf:
            if self._derived is None or self._derived[0] is not result.leaf:
                self._derived = (result.leaf, Sketch.from_result(result))
                self.editor.set_sketch(self._derived[1], fit=True)
        elif self._fit_sketch:
            self.editor.view.fit()
        self._fit_sketch = False
        self._stage_timer.stop()
        self._show_timings(outcome)
        if self.scan is not None:
            self.tasks.submit(
                "fidelity",
                outcome.request.id,
                fidelity_sections,
                result.triangle_mesh,
                self.scan,
                result.length,
            )
        self._update_poisson()
        self.result_shown.emit(outcome)

    def _on_failed(self, request_id: int, message: str) -> None:
        if request_id < self._shown_id:
            return
        self.status_text.setStyleSheet("color: #b00020")
        self.status_text.setText(f"Failed: {message}")
        self.viewport.set_message(message)
        if (
            self._fallback is not None
            and request_id >= self._fallback[3]
            and self.result is not None
        ):
            doc, path, params, _ = self._fallback
            self._fallback = None
            self.doc, self.path = doc, path
            self.panel.set_params(params)
            self._saved_params = params
            self._derived = None
            self._set_scan(self._fallback_scan)
            self.editor.set_sketch(doc.sketch or Sketch.from_result(self.result), fit=True)
            self._title = Path(path).name if path else self._title
            self._update_title()
            self.show_error("Cannot reconstruct this leaf", message)
        self.failure_shown.emit(message)

    def _show_timings(self, outcome: Outcome) -> None:
        ms = [f"{name} {1000 * t:.0f} ms" for name, t in outcome.timings.items()]
        total = sum(outcome.timings.values())
        params = outcome.result.params
        self.status_text.setStyleSheet("")
        self.status_text.setText(
            f"K={params.k}, grid {params.grid}: " + " · ".join(ms) + f" (total {1000 * total:.0f}"
            " ms; stages not listed came from the cache)"
        )
        for note in outcome.result.warnings:
            self.status_text.setText(self.status_text.text() + f" — note: {note}")

    def _on_task_done(self, kind: str, token: object, value: object) -> None:
        if kind == "scan" and token == self._scan_due:
            self._switch(Doc(value.extraction.leaf), token, Path(token).name, None, scan=value)
            self._add_recent(token)
        elif kind == "fidelity" and token == self._shown_id and self.scan is not None:
            self.fidelity = (token, value)
            self._show_measurements()
        elif kind == "poisson" and token is self._poisson_leaf:
            self.viewport.set_layer("poisson", [value])

    def _on_task_failed(self, kind: str, token: object, message: str) -> None:
        if kind == "scan" and token == self._scan_due:
            self._scan_due = None
            self.status_text.setStyleSheet("color: #b00020")
            self.status_text.setText(f"Failed: {message}")
            self.show_error("Cannot open the scan", message)
            self.failure_shown.emit(message)
        elif kind == "fidelity" and token == self._shown_id and self.scan is not None:
            self.fidelity = (token, [("Scan → mesh distance", [("Failed", message)])])
            self._show_measurements()
        elif kind == "poisson" and token is self._poisson_leaf:
            self._poisson_leaf = None
            self.status_text.setText(self.status_text.text() + f" — Poisson failed: {message}")

    def _show_measurements(self) -> None:
        """Fill the panel once the shown result is measured; with a scan open, its distances
        follow (measurements_shown fires when they are in)."""
        result = self.result
        if result is None or self._measured_id != self._shown_id:
            return
        sections = measurement_rows(result)
        waiting = self.scan is not None and (
            self.fidelity is None or self.fidelity[0] != self._shown_id
        )
        if waiting:  # the scan's sections first: with a scan open, they are what matters
            sections.insert(0, ("Scan → mesh distance", [("Computing…", "")]))
        elif self.fidelity is not None:
            sections[:0] = self.fidelity[1]
        self.measurements.clear()
        for title, rows in sections:
            section = QTreeWidgetItem([title, ""])
            for label, value in rows:
                QTreeWidgetItem(section, [label, value])
            self.measurements.addTopLevelItem(section)
            section.setExpanded(True)
        if not waiting:
            self.measurements_shown.emit()

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
        self.tasks.shutdown()
        self.viewport.close_plotter()
        event.accept()
