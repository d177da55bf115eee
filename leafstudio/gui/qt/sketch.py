"""The 2D sketch editor on the leaf plane: click, drag and delete control points of the boundary
(a closed spline) and of each vein (open splines), and set each vein point's height.

Drawing follows the hand: a click adds a point to the chosen curve (a point of that curve is
dragged); selecting a point of another curve takes the Select tool, or Ctrl or Shift. A new vein
exists from its first click, which snaps onto a vein nearby (a branch). The view moves only when
asked (Fit, the wheel) or when a document opens. With Mirror on, each edit is reflected across
the midrib's curve (gui/model/midrib.py). Where the boundary crosses itself it is marked in
red. A side view (gui/qt/profile_view.py) shows the chosen vein's heights along it, with
handles to drag. The drawing itself is SketchView (sketch_view.py).

The editor never changes the document itself: it emits `preview(sketch)` while a point is dragged
(so the 3D view follows) and `committed(before, after, text)` when an edit is done; the session
turns the latter into an undo step. Whatever changes the document's sketch (undo, Grow veins,
Mirror) hands it to `set_sketch`, so the editor always edits the document's sketch; its own edits
come back as the sketch it already shows and are ignored.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from PySide6.QtCore import QPoint, Qt
from PySide6.QtGui import QPalette, QResizeEvent
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from leafstudio.forms import VENATION_KINDS, definition
from leafstudio.gui.model.sketch_model import BOUNDARY, Sketch
from leafstudio.gui.qt.profile_view import ProfileView
from leafstudio.gui.qt.sketch_view import CROSSING_COLOR, SketchView
from leafstudio.gui.qt.turns import later


class SketchEditor(QWidget):
    """The sketch view with its tools: which curve to draw, a new vein, delete, height, fit,
    and the chosen vein's heights along it (a linear profile, or the side view's handles)."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.view = SketchView(self)
        self.curve = QComboBox()
        self.curve.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToContents)
        self.curve.setMinimumContentsLength(8)
        self.curve.setToolTip("The curve that a click adds points to: the boundary or a vein.")
        self.new_vein = QPushButton("New vein")
        self.new_vein.setToolTip("Start a new vein; then click along it from its base to its tip.")
        self.delete = QPushButton("Delete")
        self.delete.setToolTip("Delete the selected point (also Del, or right-click a point).")
        self.height = QDoubleSpinBox()
        self.height.setRange(-1e3, 1e3)
        self.height.setDecimals(4)
        self.height.setKeyboardTracking(False)
        self.height.setToolTip(
            "Height of the selected vein point above the leaf's plane (negative: below it). "
            "A vein clicked out on a drawn leaf stands on a smooth dome over the outline; a "
            "height set here or in the side view raises or lowers that point off the dome (the "
            "vein moves only up to its neighbouring points), and stays so as the outline changes."
        )
        fit = QPushButton("Fit")
        fit.setToolTip("Zoom to the whole leaf.")
        self.select = QPushButton("Select")
        self.select.setCheckable(True)
        self.select.setToolTip(
            "Click a point of any curve to select and drag it (also Ctrl- or Shift-click), "
            "instead of adding points."
        )
        self.mirror = QCheckBox("Mirror")
        self.mirror.setToolTip(
            "Keep the boundary and the side veins symmetric about the midrib (vein 1), following "
            "its curve: each edit is reflected onto the other side, as far from the midrib at "
            "the same place along it."
        )
        self.profile_start, self.profile_end = QDoubleSpinBox(), QDoubleSpinBox()
        for box in (self.profile_start, self.profile_end):
            box.setRange(-1e3, 1e3)
            box.setDecimals(4)
            box.setKeyboardTracking(False)
        self.profile = QPushButton("Set vein profile")
        self.profile.setToolTip(
            "Set the heights of the whole chosen vein at once: from the first value at its start "
            "to the second at its end, in a straight line along it."
        )
        curves, point, whole = QHBoxLayout(), QHBoxLayout(), QHBoxLayout()  # a narrow dock fits
        for widget in (self.curve, self.new_vein, self.select, self.delete):
            curves.addWidget(widget)
        for widget in (QLabel("Height"), self.height, self.mirror, fit):
            point.addWidget(widget)
        for widget in (QLabel("Start"), self.profile_start, QLabel("end"), self.profile_end):
            whole.addWidget(widget)
        whole.addWidget(self.profile)
        for row in (curves, point, whole):
            row.addStretch(1)
        hint = QLabel(
            "Click: add a point to the chosen curve · drag its points: move · Ctrl/Shift-click: "
            "select any point · right-click or Del: delete · wheel: zoom"
        )
        hint.setWordWrap(True)
        hint.setForegroundRole(QPalette.ColorRole.PlaceholderText)
        # why an edit was not mirrored, over the view's top (in a layout, its showing would
        # resize the view, which keeps its fitted area in view: the drawing would jump)
        self.mirror_note = QLabel(self.view)
        self.mirror_note.setWordWrap(True)
        self.mirror_note.setStyleSheet(
            f"color: {CROSSING_COLOR}; background: palette(base); border: 1px solid "
            f"{CROSSING_COLOR}; padding: 3px"
        )
        self.mirror_note.hide()
        # a loaded leaf drawn by its edited sketch (Session.outline_note), over the view's foot
        self.outline_note = QLabel(self.view)
        self.outline_note.setWordWrap(True)
        self.outline_note.setStyleSheet(
            "color: #3d2f00; background: #fff4cc; border: 1px solid #c9a227; padding: 3px; "
            "padding-right: 22px"  # room for its close control
        )
        # it stays while the sketch draws the leaf: clicks, drags and the wheel go through it to
        # the sketch (it took them: at the window's 1500 x 920 it covers the view's foot, 50 of
        # its 262 pixels, where a click added no point; review32)
        self.outline_note.setAttribute(Qt.WidgetAttribute.WA_TransparentForMouseEvents)
        self.outline_note.hide()
        # its close control, the one part of it that takes a click: dismissed, the note stays
        # hidden until it has something new to say (it could not be dismissed, and hid the
        # sketch's foot while the sketch drew the leaf: closing32)
        self.outline_close = QToolButton(self.view)
        self.outline_close.setText("×")
        self.outline_close.setAutoRaise(True)
        self.outline_close.setToolTip("Hide this note (the status line's tooltip keeps it)")
        self.outline_close.clicked.connect(self._dismiss_outline_note)
        self.outline_close.hide()
        self._dismissed = ""  # the outline note's text the user closed
        # a new document whose sketch is not known yet (a loaded leaf's comes with its result)
        self.waiting = QLabel("Waiting for the leaf: its sketch shows once it is reconstructed.")
        self.waiting.setParent(self.view)
        self.waiting.setWordWrap(True)
        self.waiting.hide()
        self._waiting = False
        self._due: tuple[Sketch, bool] | None = None  # an awaited sketch, shown next turn
        layout = QVBoxLayout(self)
        layout.setContentsMargins(4, 4, 4, 4)
        layout.addLayout(curves)
        layout.addLayout(point)
        layout.addLayout(whole)
        self.profile_view = ProfileView()
        layout.addWidget(self.profile_view)
        layout.addWidget(self.view, 1)
        layout.addWidget(hint)

        self.preview = self.view.preview
        self.committed = self.view.committed
        self.mirror_changed = self.view.mirror_changed
        self.new_vein.clicked.connect(self.view.new_vein)
        self.delete.clicked.connect(self.view.delete_selected)
        fit.clicked.connect(self.view.fit)
        self.select.toggled.connect(self._set_select_tool)
        self.mirror.toggled.connect(self._set_mirror)
        self.view.mirror_problem.connect(self._show_mirror_note)
        self.profile.clicked.connect(
            lambda: self.view.set_profile(self.profile_start.value(), self.profile_end.value())
        )
        self.height.valueChanged.connect(self.view.set_height)
        self.profile_view.dragged.connect(self.view.preview_heights)
        self.profile_view.released.connect(self.view.commit_heights)
        self.curve.activated.connect(self._choose_curve)
        self.view.selection_changed.connect(self._sync_tools)
        self._sync_tools()

    def set_sketch(self, sketch: Sketch, fit: bool = False) -> None:
        """Show `sketch` (see SketchView.set_sketch); a new document (`fit`) clears the note
        about an edit not mirrored. An awaited sketch (wait_for_sketch: a loaded leaf's, derived
        with its first result) is drawn a turn later: the session's work on that result and the
        drawing of its points are then two pauses of the main thread, not one (issue 24: 40 ms
        for a 2-million-point scan's)."""
        if self._waiting and self._due is None:
            self._due = (sketch, fit)
            later(self, self._show_due)
            return
        self._due = None
        if self._waiting:
            self._waiting = False
            self.waiting.hide()
            self.setEnabled(True)
        if sketch is self.view.sketch and not fit:
            return  # the editor's own edit, back from the session: shown already
        if fit:
            self._show_mirror_note("")
        self.view.set_sketch(sketch, fit)

    def _show_due(self) -> None:
        if self._due is not None:
            self.set_sketch(*self._due)

    def drop_edit(self) -> None:
        """End a drag (of a point or a side view handle) or a run of key presses under way, with
        no step: the document changed under it (a new document, an undo, a redo), and its step
        would start from a sketch that is no longer the document's. The window calls it before
        the new document's sketch arrives, which may be only with its first result."""
        self.view.drop_drag()
        self.profile_view.drop_edit()

    def wait_for_sketch(self) -> None:
        """A new document whose sketch is not known yet (Session.sketch_waiting): drop the
        sketch shown and take no edit until set_sketch. An edit of the previous document's
        sketch would be committed onto the new one, replacing its leaf."""
        self.drop_edit()
        self.view.set_sketch(Sketch(), fit=True)
        self._show_mirror_note("")
        self._waiting, self._due = True, None
        self.setEnabled(False)
        self._over_view(self.waiting)
        self.waiting.show()

    def _over_view(self, label: QLabel, foot: bool = False) -> None:
        """Lay a note over the view's top (or `foot`), inside the frame and the scroll bars."""
        area = self.view.viewport().geometry()
        width = max(120, area.width() - 16)
        label.setFixedSize(width, label.heightForWidth(width))
        top = area.bottom() - 8 - label.height() if foot else area.top() + 8
        label.move(area.left() + 8, top)
        label.raise_()

    def show_outline_note(self, text: str) -> None:
        """Say, over the sketch's foot, that the leaf is drawn by this sketch and no longer by
        the scan's (or file's) own outline and veins (Session.outline_note); "" hides it."""
        note, close = self.outline_note, self.outline_close
        if text != note.text():
            note.setText(text)
        if not text:  # the leaf's own curves back (an undo), or a new document
            self._dismissed = ""
        shown = bool(text) and text != self._dismissed
        if shown:
            self._over_view(note, foot=True)
            size = close.sizeHint()
            close.move(note.geometry().topRight() - QPoint(size.width() - 1, -1))
            close.raise_()
        note.setVisible(shown)
        close.setVisible(shown)

    def _dismiss_outline_note(self) -> None:
        """The note's close control: hidden while it says the same."""
        self._dismissed = self.outline_note.text()
        self.show_outline_note(self._dismissed)

    def _set_select_tool(self, on: bool) -> None:
        self.view.select_tool = on

    def _set_mirror(self, on: bool) -> None:
        """The checkbox: the view's sketch takes the flag at once (so edits mirror even with
        nothing listening); the session records it as an undo step (`mirror_changed`)."""
        self.view.sketch = replace(self.view.sketch, symmetric=on)
        self.view.mirror_changed.emit(on)

    def resizeEvent(self, event: QResizeEvent) -> None:
        super().resizeEvent(event)
        if self.mirror_note.isVisible():  # the notes keep to the view's width
            self._show_mirror_note(self.mirror_note.text())
        if self.outline_note.isVisible():
            self.show_outline_note(self.outline_note.text())
        if self._waiting:
            self._over_view(self.waiting)

    def _show_mirror_note(self, text: str) -> None:
        """Say why an edit was not mirrored, over the sketch (a drag updates it without any
        dialog); cleared by the next mirrored edit, a new document or Mirror off."""
        note = self.mirror_note
        if text != note.text():
            note.setText(text)
        if text:
            self._over_view(note)
        note.setVisible(bool(text))

    def _choose_curve(self, row: int) -> None:
        self.view.active = BOUNDARY if row == 0 else row - 1
        self.view.selected = None
        self.view.set_sketch(self.view.sketch)

    def _sync_tools(self) -> None:
        view = self.view
        count = len(view.sketch.veins)
        names = ["Boundary"] + [f"Vein {i + 1}" for i in range(count)]
        if view.active == count:
            names.append(f"Vein {count + 1} (new: click to start it)")
        self.curve.blockSignals(True)
        if [self.curve.itemText(i) for i in range(self.curve.count())] != names:
            self.curve.clear()
            self.curve.addItems(names)
        self.curve.setCurrentIndex(view.active + 1)
        self.curve.blockSignals(False)
        selected = view.selected
        self.delete.setEnabled(selected is not None)
        on_vein = selected is not None and selected[0] != BOUNDARY
        self.height.blockSignals(True)
        self.height.setEnabled(on_vein)
        self.height.setSingleStep(0.01 * view.sketch.extent())
        self.height.setValue(
            float(view.sketch.veins[selected[0]][selected[1], 2]) if on_vein else 0.0
        )
        self.height.blockSignals(False)
        self.select.blockSignals(True)
        self.select.setChecked(view.select_tool)
        self.select.blockSignals(False)
        self.mirror.blockSignals(True)
        self.mirror.setChecked(view.sketch.symmetric)
        self.mirror.blockSignals(False)
        if not view.sketch.symmetric:
            self._show_mirror_note("")
        on_vein = 0 <= view.active < count
        self.profile_view.set_vein(view.sketch, view.active)
        for widget in (self.profile_start, self.profile_end, self.profile):
            widget.setEnabled(on_vein)
        if on_vein:
            vein = view.sketch.veins[view.active]
            for box, value in ((self.profile_start, vein[0, 2]), (self.profile_end, vein[-1, 2])):
                box.blockSignals(True)
                box.setSingleStep(0.01 * view.sketch.extent())
                box.setValue(float(value))
                box.blockSignals(False)


def add_grow_row(editor: QWidget, grow: Callable[[str], None]) -> None:
    """A "Grow veins" row in the sketch editor, above its drawing (the editor's layout is a
    column of tool rows, then the view)."""
    kind = QComboBox()
    kind.addItems(list(VENATION_KINDS))
    for i, name in enumerate(VENATION_KINDS):
        kind.setItemData(i, definition(name, "venation"), Qt.ItemDataRole.ToolTipRole)
    button = QPushButton("Grow veins")
    button.setToolTip(
        "Replace the veins by veins of this kind grown inside the outline (space colonization, "
        "Runions et al. 2005): an ordinary sketch, editable, one undo step."
    )
    button.clicked.connect(lambda: grow(kind.currentText()))
    row = QHBoxLayout()
    row.addWidget(button)
    row.addWidget(kind)
    row.addStretch(1)
    layout = editor.layout()
    views = [i for i in range(layout.count()) if layout.itemAt(i).widget() is editor.view]
    layout.insertLayout(views[0] if views else layout.count(), row)
    editor.grow_button, editor.grow_kind = button, kind
