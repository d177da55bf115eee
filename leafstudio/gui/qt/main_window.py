"""The main window: menus, docks (parameters, layers, sketch, measurements), status bar.

The window is a view of a Session (session.py, no Qt): the document, its parameters, results and
undo history live there. The window forwards edits to it, hands it the worker's reports, and
draws what it says. A failure leaves the last good result on screen and says why; a file that
cannot be opened or reconstructed leaves the current document.
"""

from __future__ import annotations

import json
import time
from dataclasses import replace
from pathlib import Path

from PySide6.QtCore import QSettings, Qt, QTimer, Signal
from PySide6.QtGui import (
    QAction,
    QCloseEvent,
    QDragEnterEvent,
    QDropEvent,
    QKeySequence,
)
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDockWidget,
    QFileDialog,
    QHBoxLayout,
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

from leafstudio.assets.export import TEXTURED_SUFFIXES, save_mesh
from leafstudio.assets.writers import MESH_SUFFIXES
from leafstudio.errors import LeafError
from leafstudio.gui.model.jobs import Job
from leafstudio.gui.model.layers import LAYERS, MESH_COLORINGS
from leafstudio.gui.model.measurements import measurement_rows
from leafstudio.gui.model.scans import ScanData
from leafstudio.gui.model.session import Framing, Session, State
from leafstudio.gui.model.textures import TEXTURE, TEXTURE_LABEL
from leafstudio.gui.qt import explain, forms_dock
from leafstudio.gui.qt.controls import ParamPanel
from leafstudio.gui.qt.sketch import SketchEditor
from leafstudio.gui.qt.status import StatusText
from leafstudio.gui.qt.viewport import CAMERAS, Viewport
from leafstudio.gui.qt.worker import PIPELINE, Outcome, Worker
from leafstudio.model import Params
from leafstudio.sources.demos import DEMOS
from leafstudio.sources.files import LEAF_SUFFIXES, save_leaf
from leafstudio.sources.scan import SCAN_SUFFIXES

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


def _file_filter() -> str:
    patterns = " ".join(f"*{s}" for s in LEAF_SUFFIXES)
    return f"Leaves ({patterns});;{_photo_filter()};;{_scan_filter()}"


def _photo_filter() -> str:
    from leafstudio.sources.photo import PHOTO_SUFFIXES

    return f"Photos of a leaf ({' '.join(f'*{s}' for s in PHOTO_SUFFIXES)})"


def _scan_filter() -> str:
    patterns = " ".join(f"*{s}" for s in SCAN_SUFFIXES)
    return f"Leaf scans ({patterns});;All files (*)"


class MainWindow(QMainWindow):
    """The app's window. `settings` holds layout, last params and recent files."""

    result_shown = Signal(object)  # Outcome, after it is on screen
    measurements_shown = Signal()  # the panel is complete (with the scan's distances, if any)
    failure_shown = Signal(str)
    texture_shown = Signal()  # a new texture image is on the mesh (the Texture colouring)
    notice_shown = Signal(str)  # a message that is not a failure (a project's photo is missing)

    def __init__(self, settings: QSettings, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.settings = settings
        self.setWindowTitle(APP_NAME)
        self.setAcceptDrops(True)
        self.resize(1500, 920)

        self.last_error_box: QMessageBox | None = None
        self._scan_shown: ScanData | None = None  # the scan whose layer is drawn

        self.worker = Worker(self)
        self.worker.measure_after_drawn = True  # measuring would slow the render down
        self.session = Session(self.worker.submit_pipeline, run=self.worker.start)
        self.viewport = Viewport(self)
        self.viewport.rendered.connect(self._on_rendered)
        self.setCentralWidget(self.viewport)
        self.panel = ParamPanel()
        self.editor = SketchEditor()
        self.layer_list, self.edges = QListWidget(), QCheckBox("Show mesh edges")
        self.measurements = QTreeWidget()
        self.status_text = StatusText()  # not a QLabel: see status.py
        self._build_docks()
        self._build_menus()
        self.statusBar().addWidget(self.status_text, 1)

        self.worker.stage_started.connect(self._on_stage)
        self.worker.yielded.connect(self._on_yielded)
        self.worker.done.connect(self._on_measured)
        self.worker.failed.connect(self._on_pipeline_failed)
        self._stage_timer = QTimer(self)
        self._stage_timer.setSingleShot(True)
        self._stage_timer.setInterval(STAGE_LABEL_MS)
        self._stage_timer.timeout.connect(self._show_stage)
        self._stage = ""
        session = self.session
        session.state_changed.connect(self._on_state)
        session.result_shown.connect(self._on_result)
        session.failed.connect(self._on_session_failed)
        session.cleared.connect(self._on_cleared)
        session.sketch_shown.connect(self.editor.set_sketch)
        session.sketch_waiting.connect(self.editor.wait_for_sketch)  # a loaded leaf: none yet
        session.crossing.connect(self.editor.view.set_crossings)
        session.noticed.connect(self._on_notice)
        session.history.changed.connect(self._on_history)
        session.opening.connect(self._on_opening)
        session.opened.connect(self._add_recent)
        session.open_failed.connect(self._on_open_failed)
        side = session.side
        side.fidelity_shown.connect(self._show_measurements)
        side.poisson_shown.connect(lambda pieces: self.viewport.set_layer("poisson", pieces))
        side.texture_shown.connect(self._on_texture)
        side.note.connect(self._on_side_note)
        self.panel.changed.connect(self._on_params)
        self.panel.released.connect(self._on_params_released)
        self.panel.released.connect(self._on_rendered)  # measure what the drag left shown
        self.editor.preview.connect(session.preview_sketch)
        self.editor.committed.connect(lambda _b, after, text: session.commit_sketch(after, text))
        self.editor.mirror_changed.connect(session.set_symmetric)  # saved with the sketch
        forms_dock.install(self)  # the Forms gallery; Grow veins in the sketch editor
        explain.install(self)  # the Steps view, exports for slides, layer help, view aids
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
        self.coloring.addItem(f"Show the {TEXTURE_LABEL}", TEXTURE)
        self.coloring.setToolTip(
            "What the mesh's colours show: its height above the leaf's plane, how it bends "
            "(mean or Gaussian curvature; red bends one way, blue the other), or the texture an "
            "export writes (blade and veins, the photo the leaf came from, or the image chosen "
            "in Export mesh) mapped through the mesh's UVs, as Blender shows it."
        )
        self.coloring.currentIndexChanged.connect(self._on_coloring)
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
        self._measurements_due = False
        self.measurements_dock.visibilityChanged.connect(
            lambda visible: visible and self._measurements_due and self._show_measurements()
        )
        # More docks (e.g. a forms gallery, gui/qt/forms_dock.py) are added here with self._dock;
        # a dock that makes a leaf calls self.session.new_document(leaf, sketch, title=...),
        # one undo step, and the window shows it like any other document.
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
        self._action(
            files,
            "Open &photo…",
            self.open_photo_dialog,
            None,
            "Open a photo or scan of one leaf on a plain background: its outline, grown veins",
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
            "Write the mesh: .glb, .gltf, .obj (textured), .ply, .stl, .3mf, .vtp or .vtk",
        )
        self._action(
            files,
            "Export so&lid for printing…",
            self.export_solid_dialog,
            None,
            "Write the leaf as a closed solid of a chosen thickness (.stl, .3mf, .obj, .ply, .glb)",
        )
        self._action(files, "Export &screenshot…", self.export_screenshot_dialog, "Ctrl+Shift+E")
        files.addSeparator()
        self.quit_action = self._action(files, "&Quit", self.close, keys.Quit)

        edit = bar.addMenu("&Edit")
        self.undo_action = self._action(edit, "&Undo", self.session.undo, keys.Undo)
        self.redo_action = self._action(edit, "&Redo", self.session.redo)
        redo_keys = [QKeySequence(keys.Redo), QKeySequence("Ctrl+Shift+Z"), QKeySequence("Ctrl+Y")]
        self.redo_action.setShortcuts(list(dict.fromkeys(k for k in redo_keys if not k.isEmpty())))
        self._on_history()

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
        # Kept in Python: walking menuBar().actions() can hand back a stale wrapper of another
        # type (a QSurface) under PySide6, seen intermittently in the GUI tests.
        self.menus = {"File": files, "Edit": edit, "View": view, "Demos": demos, "Help": about}

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
        self.session.state = replace(self.session.state, params=self.panel.params())

    def _on_history(self) -> None:
        """Undo and redo name what they would do, and are off when there is nothing to do."""
        history = self.session.history
        self.undo_action.setEnabled(history.can_undo())
        self.undo_action.setText(f"&Undo {history.undo_text()}".rstrip())
        self.redo_action.setEnabled(history.can_redo())
        self.redo_action.setText(f"&Redo {history.redo_text()}".rstrip())
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
    def _update_title(self) -> None:
        state = self.session.state
        name = Path(state.path).name if state.path else state.title
        self.setWindowTitle(f"{name}[*] — {APP_NAME}")
        self.setWindowModified(self.session.is_modified())

    def _confirm_discard(self) -> bool:
        """Ask what to do with unsaved changes; True when it is fine to go on."""
        if not self.session.is_modified():
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

    def open_demo(self, name: str) -> None:
        """Open a built-in leaf with the paper's K."""
        if self._confirm_discard():
            self.session.open_demo(name)

    def open_path(self, path: str, as_scan: bool = False) -> Job:
        """Open a file (Session.open_path: read off the main thread, as every command reads it);
        a failure says why and keeps the current leaf. The reading job's handle."""
        return self.session.open_path(path, as_scan=as_scan)

    def _on_opening(self, path: str, what: str) -> None:
        name = Path(path).name
        text = {
            "photo": f"Finding the leaf in the photo {name}…",
            "scan": f"Reading the scan {name} and extracting its leaf…",
        }
        self.status_text.setStyleSheet("")
        self.status_text.setText(text.get(what, f"Opening {name}…"))

    def _on_open_failed(self, what: str, message: str) -> None:
        self.status_text.setStyleSheet("color: #b00020")
        self.status_text.setText(f"Failed: {message}")
        self.show_error(f"Cannot open the {what}", message)
        self.failure_shown.emit(message)

    def open_dialog(self) -> None:
        """File > Open."""
        path = self._ask_to_open("Open a leaf", _file_filter())
        if path:
            self.open_path(path)

    def open_photo_dialog(self) -> None:
        """File > Open photo."""
        path = self._ask_to_open("Open a photo of a leaf", _photo_filter())
        if path:
            self.open_path(path)

    def open_scan_dialog(self) -> None:
        """File > Open scan."""
        path = self._ask_to_open("Open a leaf scan", _scan_filter())
        if path:
            self.open_path(path, as_scan=True)

    def _ask_to_open(self, title: str, filters: str) -> str:
        """A file chosen in an open dialog beside the current file, once unsaved changes are
        dealt with; "" when cancelled."""
        if not self._confirm_discard():
            return ""
        path = self.session.state.path
        start = str(Path(path).parent) if path else str(Path.home())
        return QFileDialog.getOpenFileName(self, title, start, filters)[0]

    def new_sketch(self) -> None:
        """File > New sketch: an empty sketch to draw a leaf in."""
        if not self._confirm_discard():
            return
        self.session.new_sketch()
        self.sketch_dock.show()
        self.sketch_dock.raise_()

    def save(self) -> bool:
        """File > Save: write the project; Save as when it has no project file yet."""
        path = self.session.state.path
        if path is None or not path.lower().endswith(PROJECT_SUFFIX):
            return self.save_as()
        return self.save_to(path)

    def save_as(self) -> bool:
        """File > Save as."""
        start = self.session.state.path or str(Path.home() / f"leaf{PROJECT_SUFFIX}")
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
        state = self.session.state
        if state.leaf is None:
            self.show_error("Nothing to save", "The sketch needs at least 3 boundary points.")
            return False
        sketch = state.sketch.to_dict() if state.sketch is not None else None
        photo = state.photo.entry(path) if state.photo is not None else None
        try:
            save_leaf(state.leaf, path, state.params, sketch, photo)
        except (LeafError, OSError) as exc:
            self.show_error("Cannot save", str(exc))
            return False
        self.session.saved(path)
        self._add_recent(path)
        return True

    def save_mesh(self, path: str, thickness: str | None = None, texture: object = None) -> bool:
        """Write the shown mesh to `path` (by its suffix, with normals, UVs and a texture where
        the format holds them); `thickness` ("0.01" of the length, or "0.4mm") makes it a closed
        solid; `texture` is None (the leaf's: what the Texture colouring shows), "auto"
        (generated from the leaf), "none", "photo" (the photo the leaf was found in) or an image
        file, mapped as `reconstruct --texture` maps it (SideJobs.texture_option)."""
        result = self.session.result
        if result is None:
            self.show_error("Nothing to export", "There is no reconstructed mesh yet.")
            return False
        try:
            option = self.session.side.texture_option(texture)
            solid = None
            if thickness is not None:
                from leafstudio.assets.solid import thickness_in_mesh_units

                solid = thickness_in_mesh_units(thickness, result.length)
            save_mesh(result, path, texture=option, thickness=solid)
        except (LeafError, OSError) as exc:
            self.show_error("Cannot export the mesh", str(exc))
            return False
        return True

    def export_mesh_dialog(self) -> None:
        """File > Export mesh; the texture chosen is the one the Texture colouring shows next."""
        patterns = " ".join(f"*{s}" for s in MESH_SUFFIXES)
        path, _ = QFileDialog.getSaveFileName(self, "Export the mesh", "", f"Meshes ({patterns})")
        if not path:
            return
        path = path if Path(path).suffix else path + ".ply"
        texture = self._texture_choice(path)
        if texture is None:
            return
        try:
            option = self.session.side.texture_option(texture)
        except LeafError as exc:
            self.show_error("Cannot export the mesh", str(exc))
            return
        textured = Path(path).suffix.lower() in TEXTURED_SUFFIXES
        if self.save_mesh(path, texture=option) and textured:
            self.session.choose_texture(option)

    TEXTURE_CHOICES = (
        "Generated from the leaf (blade and veins)",
        "None (UVs and a plain material)",
        "An image file… (mapped through the UVs)",
    )
    PHOTO_CHOICE = "The photo the leaf was found in ({name})"

    def _texture_choice(self, path: str) -> object:
        """The texture for a format that carries one (.glb, .gltf, .obj): "auto", "none",
        "photo" or an image path; None if the user cancels. The leaf's current texture is
        offered first (a photo-opened leaf's photo)."""
        from PySide6.QtWidgets import QInputDialog

        from leafstudio.sources.leafphoto import PhotoTexture

        if Path(path).suffix.lower() not in TEXTURED_SUFFIXES:
            return "auto"
        choices = list(self.TEXTURE_CHOICES)
        photo = self.session.state.photo
        if photo is not None and photo.exists():
            choices.append(self.PHOTO_CHOICE.format(name=photo.image.name))
        current = self.session.texture()
        if current == "none":
            first = 1
        elif (
            isinstance(current, PhotoTexture)
            and len(choices) > 3
            and (photo is not None and Path(current.image) == photo.image)
        ):
            first = 3
        elif current == "auto":
            first = 0
        else:
            first = 2
        choice, ok = QInputDialog.getItem(
            self, "Texture", "The mesh's texture:", choices, first, False
        )
        if not ok:
            return None
        if choice == self.TEXTURE_CHOICES[0]:
            return "auto"
        if choice == self.TEXTURE_CHOICES[1]:
            return "none"
        if choice != self.TEXTURE_CHOICES[2]:
            return "photo"
        image, _ = QFileDialog.getOpenFileName(
            self, "The texture image", "", "Images (*.png *.jpg *.jpeg *.tif *.tiff *.bmp *.webp)"
        )
        return image or None

    def export_solid_dialog(self) -> None:
        """File > Export solid: the thickness (a fraction of the length, or with its unit), then
        the file."""
        from PySide6.QtWidgets import QInputDialog

        text, ok = QInputDialog.getText(
            self,
            "Export a solid",
            "Thickness: a fraction of the leaf length (0.01), or a length with its unit for a leaf "
            "in millimetres (0.4mm)",
            text="0.01",
        )
        if not ok:
            return
        patterns = "*.stl *.3mf *.obj *.ply *.glb"
        path, _ = QFileDialog.getSaveFileName(self, "Export the solid", "", f"Solids ({patterns})")
        if path:
            self.save_mesh(path if Path(path).suffix else path + ".stl", thickness=text)

    def export_screenshot_dialog(self) -> None:
        """File > Export screenshot: the 3D view as PNG."""
        path, _ = QFileDialog.getSaveFileName(self, "Export a screenshot", "", "PNG (*.png)")
        if path:
            path = path if path.lower().endswith(".png") else path + ".png"
            if not self.viewport.image().save(path):
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
    def _on_params(self, params: Params) -> None:
        self.session.set_params(params, final=not self.panel.is_dragging())

    def _on_params_released(self) -> None:
        self.session.set_params(self.panel.params(), final=True)

    def _on_layer_item(self, item: QListWidgetItem) -> None:
        key = item.data(Qt.ItemDataRole.UserRole)
        self.viewport.set_visible(key, item.checkState() == Qt.CheckState.Checked)
        if key == "poisson":
            self.session.side.set_poisson(self.viewport.visible["poisson"])

    def _on_coloring(self, row: int) -> None:
        """The Layers dock's colouring: a scalar, or the texture (made on the side lane)."""
        self.viewport.set_mesh_coloring(self.coloring.itemData(row))
        self.session.side.set_texture_shown(self.viewport.mesh_coloring == TEXTURE)

    def _on_side_note(self, note: str) -> None:
        """A side job failed without harm (the Poisson surface, the generated texture)."""
        self.status_text.setText(f"{self.status_text.text()} — {note}")

    def _on_texture(self, image: object, key: tuple) -> None:
        self.viewport.set_texture(image, key)
        self.texture_shown.emit()

    def _on_notice(self, message: str) -> None:
        """A message that is not a failure (the leaf is still shown): a box and the status."""
        self.status_text.setStyleSheet("color: #b00020")
        self.status_text.setText(message)
        self.show_error("Note", message)
        self.notice_shown.emit(message)

    # --- session reports -----------------------------------------------------------------------
    def _on_state(self, state: State, reason: str) -> None:
        if reason in ("document", "undo", "fallback"):
            self.editor.drop_edit()  # a drag or key run under way: its step would mix documents
            self.panel.set_params(state.params)
        if state.scan is not self._scan_shown:
            self._scan_shown = state.scan
            self.viewport.set_layer("scan", state.scan.pieces if state.scan is not None else [])
        self._update_title()

    def _on_cleared(self) -> None:
        self.viewport.clear()
        if (scan := self.session.state.scan) is not None:
            self.viewport.set_layer("scan", scan.pieces)
        self.measurements.clear()
        self.status_text.setStyleSheet("")
        self.status_text.setText(self.session.message)

    def _on_result(self, outcome: Outcome, framing: Framing | None) -> None:
        result = outcome.result
        start = time.perf_counter()
        frame = self.session.view_frame() or result.frame
        how = None if framing is None else ("reset" if framing.reset else "refit")
        bounds = framing.bounds if framing is not None else None
        if how == "reset" and self.viewport.texture_key is not None:  # another leaf's image
            self.viewport.set_texture(None, None, draw=False)
        self.viewport.show_layers(outcome.layers, frame, bounds, how)
        outcome.timings["draw"] = time.perf_counter() - start
        self._stage_timer.stop()
        self._show_timings(outcome)
        self.editor.view.set_crossings(self.session.crossings)
        self.result_shown.emit(outcome)

    def _on_session_failed(self, message: str, fell_back: bool) -> None:
        self.status_text.setStyleSheet("color: #b00020")
        self.status_text.setText(f"Failed: {message}")
        self.viewport.set_message(message)
        self.editor.view.set_crossings(self.session.crossings)
        if fell_back:
            self.show_error("Cannot reconstruct this leaf", message)
        self.failure_shown.emit(message)

    # --- worker reports ------------------------------------------------------------------------
    def _on_stage(self, kind: str, request_id: int, stage: str) -> None:
        if kind == PIPELINE and request_id == self.session.last_id:
            self._stage = stage
            if not self._stage_timer.isActive():
                self._stage_timer.start()

    def _show_stage(self) -> None:
        if not self.worker.is_idle(PIPELINE):
            self.status_text.setStyleSheet("")
            self.status_text.setText(f"Running: {self._stage}…")

    def _on_yielded(self, kind: str, job_id: int, value: object) -> None:
        if kind == PIPELINE and not self.session.accept_drawable(value):
            self._on_rendered()  # not shown: no render to wait for

    def _on_rendered(self) -> None:
        """The shown result is on screen: the worker may measure it (Worker.measure_after_drawn);
        while a slider is held, not before it is let go (measuring takes the pipeline's lane
        for ~0.1 s at grid 512, which the drag's next value would wait for)."""
        if not self.panel.is_dragging():
            self.session.drawn()

    def _on_measured(self, kind: str, job_id: int, seconds: object) -> None:
        """The pipeline measured a result (side jobs answer through their handles)."""
        if kind != PIPELINE or not self.session.accept_measured(job_id):
            return
        if self.session.result is not None:
            if not self.session.message:  # not after a failure's message (Worker._failed)
                self.status_text.setText(
                    self.status_text.text() + f" · measurements {1000 * seconds:.0f} ms"
                )
            self._show_measurements()

    def _on_pipeline_failed(self, kind: str, job_id: int, exc: BaseException) -> None:
        if kind == PIPELINE:
            self.session.accept_failure(job_id, exc)

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

    def _show_measurements(self) -> None:
        """Fill the panel once the shown result is measured; with a scan open, its distances
        follow (measurements_shown fires when they are in)."""
        result, shown = self.session.result, self.session.shown
        if result is None or shown.measured_id != self.session.shown_id:
            return
        if not self.measurements_dock.isVisible():  # filled when shown: no cost while hidden
            self._measurements_due = True
            self.measurements_shown.emit()  # nothing on screen waits for it
            return
        self._measurements_due = False
        sections = measurement_rows(result)
        fidelity = shown.fidelity
        scan = self.session.state.scan
        waiting = scan is not None and (fidelity is None or fidelity[0] != shown.measured_id)
        if waiting:  # the scan's sections first: with a scan open, they are what matters
            sections.insert(0, ("Scan → mesh distance", [("Computing…", "")]))
        elif fidelity is not None:
            sections[:0] = fidelity[1]
        self.measurements.setUpdatesEnabled(False)
        self.measurements.clear()
        for title, rows in sections:
            section = QTreeWidgetItem([title, ""])
            section.addChildren([QTreeWidgetItem([label, value]) for label, value in rows])
            self.measurements.addTopLevelItem(section)
            section.setExpanded(True)
        self.measurements.setUpdatesEnabled(True)
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
        self.viewport.close_plotter()
        event.accept()
