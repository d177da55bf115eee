"""The window's file commands: open (any file, a scan, a photo, a recent one, a demo), save,
export the mesh, a solid or a screenshot. A mixin of MainWindow (main_window.py): the dialogs
are Qt's, what they decide is the session's (Session.open_path reads a file as every command
does; SideJobs.texture_option turns a texture choice into an export's option).
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtWidgets import QFileDialog, QMenu, QMessageBox

from leafstudio.assets.export import TEXTURED_SUFFIXES, save_mesh
from leafstudio.assets.units import UNITS_SAID
from leafstudio.assets.writers import MESH_SUFFIXES
from leafstudio.errors import LeafError
from leafstudio.gui.model.jobs import Job
from leafstudio.gui.qt.exports import BackgroundExports
from leafstudio.sources.files import LEAF_SUFFIXES, save_leaf
from leafstudio.sources.photo import PHOTO_SUFFIXES
from leafstudio.sources.scan import SCAN_SUFFIXES

APP_NAME = "LeafStudio"
ABOUT = (
    "<h3>LeafStudio</h3>"
    "<p>Smooth 3D leaf surfaces from a leaf's boundary and vein points.</p>"
    "<p>An implementation of Nagai &amp; Tanaya, <i>Leaf Reconstruction Based on Gaussian Mixture "
    "Model from Point Clouds of Leaf Boundaries and Veins</i>: a PCA plane, a 2D multi-level "
    "partition-of-unity implicit for the leaf region, a height guide from the veins, a Gaussian "
    "mixture fitted by EM, and a mesh trimmed at the margin.</p>"
)
PROJECT_SUFFIX = ".leaf.json"
MAX_RECENT = 8


def _file_filter() -> str:
    patterns = " ".join(f"*{s}" for s in LEAF_SUFFIXES)
    return f"Leaves ({patterns});;{_photo_filter()};;{_scan_filter()}"


def _photo_filter() -> str:
    return f"Photos of a leaf ({' '.join(f'*{s}' for s in PHOTO_SUFFIXES)})"


def _scan_filter() -> str:
    patterns = " ".join(f"*{s}" for s in SCAN_SUFFIXES)
    return f"Leaf scans ({patterns});;All files (*)"


class FileCommands(BackgroundExports):
    """Open, save and export, for MainWindow (which has `session`, `settings`, `viewport`,
    `status_text`, `docks`, `show_error` and `failure_shown`)."""

    def recent_files(self) -> list[str]:
        """Recently opened or saved files, newest first."""
        value = self.settings.value("recent") or []
        return [value] if isinstance(value, str) else list(value)

    def _add_recent(self, path: str) -> None:
        path = str(Path(path).resolve())
        recent = [path] + [p for p in self.recent_files() if p != path]
        self.settings.setValue("recent", recent[:MAX_RECENT])

    def fill_recent(self, menu: QMenu) -> None:
        """File > Open recent, as it opens."""
        menu.clear()
        for path in self.recent_files():
            action = menu.addAction(path)
            action.triggered.connect(
                lambda _=False, p=path: self._confirm_discard() and self.open_path(p)
            )
        menu.setEnabled(bool(self.recent_files()))

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
        self.opened_name = name = Path(path).name
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
        """File > Open photo: the photo, then its dialog (photo_dialog.py: the leaf's length, or a
        ruler clicked on the photo, or the photo's own DPI); a leaf made at its real size has
        that length offered by the export next."""
        from PySide6.QtWidgets import QDialog

        from leafstudio.gui.model.photo_import import PhotoImport, real_length_text
        from leafstudio.gui.qt.photo_dialog import PhotoDialog

        path = self._ask_to_open("Open a photo of a leaf", _photo_filter())
        if not path:
            return
        model = PhotoImport.of(path, str(self.settings.value("photo/length", "")))
        dialog = self.photo_dialog = PhotoDialog(model, self)
        if dialog.exec() != QDialog.DialogCode.Accepted:
            return
        options = model.options()  # checked by the dialog's OK
        self.settings.setValue("photo/length", model.length.strip())
        job = self.session.open_path(path, **options)
        if model.real_size() and model.from_what() == "length":
            self.settings.setValue("export/length", model.length.strip())
        elif model.real_size():  # the leaf's real size, offered by the export next
            job.on_done(lambda document: self.settings.setValue(
                "export/length", real_length_text(document.leaf.boundary)))  # fmt: skip

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
        self.docks["Sketch"].show()
        self.docks["Sketch"].raise_()

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

    def save_mesh(
        self,
        path: str,
        thickness: str | None = None,
        texture: object = None,
        length: str | None = None,
        lod: int = 0,
    ) -> Job | None:
        """Start writing the shown mesh to `path` in the background (exports.py: the status
        bar shows its progress; an error box if it fails), by its suffix, with normals, UVs and
        a texture where the format holds them; `thickness` ("0.01" of the length, or "0.4mm")
        makes it a closed solid; `length` ("8cm") scales it to real size (`--length`), `lod`
        adds coarser levels of detail (`--lod`); `texture`
        is None (the leaf's: what the Texture colouring shows), "auto" (generated from the
        leaf), "none", "photo" (the photo the leaf was found in) or an image file, mapped as
        `reconstruct --texture` maps it (SideJobs.texture_option). The writing job's handle, or
        None when the options are refused at once (an error box says why)."""
        from leafstudio.assets.export import check_mesh_path, leaf_placement_of
        from leafstudio.assets.placement import parse_length
        from leafstudio.assets.solid import thickness_in_mesh_units

        result = self.session.result
        if result is None:
            self.show_error("Nothing to export", "There is no reconstructed mesh yet.")
            return None
        try:
            check_mesh_path(path)
            option = self.session.side.texture_option(texture)
            metres = parse_length(length) if length else None
            solid = None
            if thickness is not None:
                blade = leaf_placement_of(result).length  # the blade's length, base to apex
                per_unit = None if metres is None else metres / blade
                solid = thickness_in_mesh_units(thickness, blade, per_unit)
        except (LeafError, OSError) as exc:
            self.show_error("Cannot export the mesh", str(exc))
            return None
        return self.run_export(
            Path(path).name, save_mesh, result, path, texture=option, thickness=solid,
            length=metres, lod=lod,
        )  # fmt: skip

    LENGTH_PROMPT = (
        f"The leaf's real length, base to apex ({UNITS_SAID}): the mesh "
        "is scaled to it and written in metres (glTF, OBJ, USD) or millimetres (STL, 3MF, PLY, "
        "VTK). Empty: the leaf's own units"
    )

    def _length_choice(self) -> str | None:
        """The export's real length ("" to keep the leaf's units), None if cancelled; the last
        one given (here or in File > Open photo) is offered."""
        from PySide6.QtWidgets import QInputDialog

        last = str(self.settings.value("export/length", ""))
        text, ok = QInputDialog.getText(self, "Real size", self.LENGTH_PROMPT, text=last)
        if not ok:
            return None
        self.settings.setValue("export/length", text.strip())
        return text.strip()

    LOD_PROMPT = (
        "Levels of detail: how many coarser meshes to write beside this one, each with half the "
        "triangles of the one before (glTF and USD keep them in the file, other formats write "
        "NAME_lod1, NAME_lod2, …; --lod on the command line). 0: none"
    )

    def _lod_choice(self) -> int | None:
        """The export's levels of detail (0 for none), None if cancelled; the last one given is
        offered."""
        from PySide6.QtWidgets import QInputDialog

        from leafstudio.assets.export import MAX_LOD

        last = int(self.settings.value("export/lod", 0) or 0)
        levels, ok = QInputDialog.getInt(self, "Levels of detail", self.LOD_PROMPT, last, 0,
                                         MAX_LOD)  # fmt: skip
        if not ok:
            return None
        self.settings.setValue("export/lod", int(levels))
        return int(levels)

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
        length = self._length_choice()
        if length is None:
            return
        lod = self._lod_choice()
        if lod is None:
            return
        textured = Path(path).suffix.lower() in TEXTURED_SUFFIXES
        job = self.save_mesh(path, texture=option, length=length, lod=lod)
        if job is not None and textured:
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
        if not path:
            return
        length = self._length_choice()
        if length is not None:
            path = path if Path(path).suffix else path + ".stl"
            self.save_mesh(path, thickness=text, length=length)

    def export_screenshot_dialog(self) -> None:
        """File > Export screenshot: the 3D view as PNG."""
        path, _ = QFileDialog.getSaveFileName(self, "Export a screenshot", "", "PNG (*.png)")
        if path:
            path = path if path.lower().endswith(".png") else path + ".png"
            if not self.viewport.image().save(path):
                self.show_error("Cannot save the screenshot", f"{path}: not written")
