"""The Forms gallery: a thumbnail per shape term, choosers for the other terms, each with its
definition in plain words beside it. Choosing makes the form the document, as an editable sketch
(one undo step, through Session.new_document); "Grow veins" fills the current outline with veins
of the chosen venation (leafstudio.forms.grow_veins), one undo step too. Fold, Curl, Roll and
Twist show the document's pose, and bend an edited form or any other leaf as the Parameters
panel's sliders do (gui/model/form_documents.py).

Thumbnails are drawn once per shape and size with QPainter (outline and veins in the plane) and
cached for the process.
"""

from __future__ import annotations

from functools import partial
from typing import Any

from PySide6.QtCore import QSignalBlocker, QSize, Qt, QTimer, Signal
from PySide6.QtGui import QIcon, QImage, QPixmap
from PySide6.QtWidgets import (
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QListView,
    QListWidget,
    QListWidgetItem,
    QPushButton,
    QScrollArea,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from leafstudio.core.bend import Pose
from leafstudio.core.evaluate import blade_midrib
from leafstudio.forms import SHAPES, VENATION_KINDS, Form, definition
from leafstudio.forms.glossary import COMPARISONS
from leafstudio.forms.terms import APEXES, DEFAULT_LOBES, MARGINS, RELIEF, TOOTHED, USER_BASES
from leafstudio.gui.model.bending import can_pose, pose_terms, sheet_tip, terms_pose
from leafstudio.gui.model.form_documents import GalleryForms
from leafstudio.gui.model.form_sketch import (
    canonical_leaves,
    grow_blade,
    outline_sketch,
    with_grown_veins,
)
from leafstudio.gui.model.jobs import Run, describe
from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.gui.qt.bend_sliders import bend_leaf
from leafstudio.gui.qt.compare_view import FIRST, compare_actions
from leafstudio.gui.qt.glossary_view import glossary_actions
from leafstudio.gui.qt.leaf_picture import draw_plane
from leafstudio.gui.qt.sketch import add_grow_row
from leafstudio.gui.qt.turns import later
from leafstudio.model import Leaf

THUMBNAIL = (100, 56)  # pixels, width and height: every form is drawn base to apex across,
# and a square (84 x 84) left a band of nothing above most (rows with nothing drawn: linear 92%,
# lanceolate 77%, ovate 42%, the gallery's mean 48%; now 84%, 61%, 5%, mean 27%)
GALLERY_SPACING = 14  # pixels around each thumbnail and its name
DEBOUNCE_MS = 250
THUMBNAILS = "thumbnails"  # the worker's job kind (and lane) growing the gallery's veins
FORM = "form"  # the job kind growing a chosen form's blade (its own lane: never behind those)
_thumbnails: dict[tuple[str, tuple[int, int]], QImage] = {}
EDITED = (  # said under the shape of a form edited since it was made (form_documents.py)
    "<br><i>Edited since it was made: Fold, Curl, Roll and Twist bend it, keeping the edits; the "
    "other terms make a new leaf when you pick a shape (Undo brings this one back).</i>"
)


def thumbnail(shape: str, size: tuple[int, int] = THUMBNAIL, leaf: Leaf | None = None) -> QImage:
    """The shape's canonical form (`leaf`, when grown already) drawn in a `size` frame (outline
    filled, veins on it), sitting on the frame's lower edge so that the gallery's name right
    under it reads as its own; drawn once per shape and size, then cached."""
    key = (shape, size)
    if key not in _thumbnails:
        _thumbnails[key] = draw_leaf(
            leaf if leaf is not None else Form(shape).leaf(), size, sit=True
        )
    return _thumbnails[key]


def outline_thumbnail(shape: str, size: tuple[int, int] = THUMBNAIL) -> QImage:
    """The shape's thumbnail until its veins are grown: the outline alone (1-2 ms a shape)."""
    return draw_plane(Form(shape).outline().xy, [], size, sit=True)


def draw_leaf(leaf: Leaf, size: int | tuple[int, int], sit: bool = False) -> QImage:
    """A leaf's outline and veins seen from above, fitted in a `size` square or (width, height)
    frame: centred, or with `sit` resting on its lower edge (a pixel or two below)."""
    return draw_plane(leaf.boundary[:, :2], [v[:, :2] for v in leaf.veins], size, sit=sit)


class FormsPanel(QWidget):
    """The gallery and its choosers. `chosen(Form, picked)` fires when the user picks a shape
    (picked True) or changes a term (False; debounced); `grow(str)` when "Grow veins" is pressed,
    with the venation."""

    chosen = Signal(object, bool)
    grow = Signal(str)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.gallery = QListWidget()
        self.gallery.setViewMode(QListView.ViewMode.IconMode)
        self.gallery.setIconSize(QSize(*THUMBNAIL))
        self.gallery.setResizeMode(QListView.ResizeMode.Adjust)
        self.gallery.setMovement(QListView.Movement.Static)
        self.gallery.setSpacing(GALLERY_SPACING)  # rows apart: each name reads as its picture's
        self.gallery.setFixedHeight(2 * (THUMBNAIL[1] + 30 + 2 * GALLERY_SPACING))
        self._growing = False  # the thumbnails' veins are being grown (grow_veins)
        for name in SHAPES:
            drawn = _thumbnails.get((name, THUMBNAIL))  # veined already (an earlier window)
            if drawn is None:
                drawn = outline_thumbnail(name)
            item = QListWidgetItem(QIcon(QPixmap.fromImage(drawn)), name)
            item.setData(Qt.ItemDataRole.UserRole, name)
            item.setToolTip(f"{name}: {definition(name)}")
            self.gallery.addItem(item)
        self.shape_text = QLabel()
        self.shape_text.setWordWrap(True)

        self.apex = self._combo(("(usual)", *APEXES), "apex")
        self.base = self._combo(("(usual)", *USER_BASES), "base")
        self.margin = self._combo(tuple(MARGINS), "margin")
        self.venation = self._combo(("(usual)", *VENATION_KINDS), "venation")
        self.teeth = self._spin(QSpinBox(), 2, 300, 30, RELIEF["teeth"])
        self.lobes = self._spin(QSpinBox(), 2, 15, DEFAULT_LOBES, RELIEF["lobes"])
        self.fold = self._spin(QDoubleSpinBox(), -75, 75, 0, RELIEF["fold"], " °", 5)
        self.curl = self._spin(QDoubleSpinBox(), -1, 1, 0, RELIEF["curl"], "", 0.05)
        self.roll = self._spin(QDoubleSpinBox(), -1, 1, 0, RELIEF["roll"], "", 0.05)
        self.twist = self._spin(QDoubleSpinBox(), -1, 1, 0, RELIEF["twist"], "", 0.05)
        self.wave = self._spin(QDoubleSpinBox(), 0, 0.2, 0, RELIEF["wave"], "", 0.005)
        self.pose_boxes = {
            "fold": self.fold,
            "curl": self.curl,
            "roll": self.roll,
            "twist": self.twist,
        }
        self._edited = False  # the open form was edited since the gallery made it
        self.seed = self._spin(QSpinBox(), 0, 1_000_000, 0, RELIEF["seed"])
        self.variant = QPushButton("New variant")
        self.variant.setToolTip("Another leaf of the same kind: the next seed.")
        self.variant.clicked.connect(lambda: self.seed.setValue(self.seed.value() + 1))
        self.grow_button = QPushButton("Grow veins in the current outline")
        self.grow_button.setToolTip(
            "Replace the current leaf's veins by veins of the chosen venation grown inside its "
            "outline (space colonization, Runions et al. 2005). One undo step."
        )
        self.grow_button.clicked.connect(lambda: self.grow.emit(self.form().venation_term))

        self.texts: dict[str, QLabel] = {}
        form = QFormLayout()
        for label, widget in (
            ("Apex", self.apex),
            ("Base", self.base),
            ("Margin", self.margin),
            ("Teeth", self.teeth),
            ("Lobes", self.lobes),
            ("Venation", self.venation),
            ("Fold", self.fold),
            ("Curl", self.curl),
            ("Roll", self.roll),
            ("Twist", self.twist),
            ("Wave", self.wave),
        ):
            text = QLabel()
            text.setWordWrap(True)
            text.setStyleSheet("color: #555555;")
            text.setMinimumWidth(200)
            self.texts[label] = text
            form.addRow(label, widget)
            form.addRow("", text)
        # a pose the reconstruction would see side-on (forms.make.SIDE_ON): said where it is set
        self.pose_note = QLabel()
        self.pose_note.setWordWrap(True)
        self.pose_note.setStyleSheet("color: #b00020;")
        self.pose_note.hide()
        form.addRow("", self.pose_note)
        seed_row = QHBoxLayout()
        seed_row.addWidget(self.seed)
        seed_row.addWidget(self.variant)
        form.addRow("Seed", seed_row)
        body = QWidget()
        column = QVBoxLayout(body)
        column.addWidget(self.gallery)
        column.addWidget(self.shape_text)
        column.addLayout(form)
        column.addWidget(self.grow_button)
        self.compare_button = QPushButton("Compare forms side by side…")
        self.compare_button.setToolTip(
            "Two or four forms side by side with the terms in which they differ (View > "
            "Compare forms)."
        )
        column.addWidget(self.compare_button)
        column.addStretch(1)
        scroll = QScrollArea()  # the definitions take room: scroll rather than squeeze them
        scroll.setWidgetResizable(True)
        scroll.setWidget(body)
        outer = QVBoxLayout(self)
        outer.setContentsMargins(0, 0, 0, 0)
        outer.addWidget(scroll)

        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(DEBOUNCE_MS)
        self._timer.timeout.connect(self._emit)
        self._picked = False
        self.gallery.currentItemChanged.connect(lambda *_: self._changed(picked=True))
        self.gallery.itemClicked.connect(lambda *_: self._changed(picked=True))
        self._describe()  # nothing highlighted until a form is open (show_shape)

    def missing_veins(self) -> list[str]:
        """The shapes whose thumbnails show their outline alone."""
        return [name for name in SHAPES if (name, THUMBNAIL) not in _thumbnails]

    def grow_veins(self, start: Run) -> None:
        """Grow the veins of the thumbnails that lack them as a side job (`start`: the worker's,
        off the main thread: 0.7 s at a first start) and draw them as they come (show_veins);
        nothing while they grow, or once they are all drawn."""
        if not self._growing and (missing := self.missing_veins()):
            self._growing = True
            job = start(THUMBNAILS, canonical_leaves, missing)
            job.on_done(self.show_veins).on_failed(lambda _exc: setattr(self, "_growing", False))

    def veins_due(self) -> bool:
        """Whether thumbnails still wait for their veins (grown or drawn; not after a failure)."""
        return self._growing and bool(self.missing_veins())

    def show_veins(self, leaves: dict[str, Leaf]) -> None:
        """Redraw the thumbnails of `leaves` (shape: canonical form) with their veins, one per
        turn of the event loop (all 14 at once held the main thread 85 ms at a first start)."""
        for row in range(self.gallery.count()):
            item = self.gallery.item(row)
            shape = item.data(Qt.ItemDataRole.UserRole)
            if shape in leaves:
                later(self, partial(self._draw_thumbnail, item, shape, leaves[shape]))

    @staticmethod
    def _draw_thumbnail(item: QListWidgetItem, shape: str, leaf: Leaf) -> None:
        item.setIcon(QIcon(QPixmap.fromImage(thumbnail(shape, leaf=leaf))))

    def show_pose(self, terms: dict[str, float]) -> dict[str, float]:
        """Show the document's pose (bending.pose_terms) on Fold, Curl, Roll and Twist without
        choosing anything; returns the figures the boxes took (rounded to their decimals)."""
        for name, value in terms.items():
            with QSignalBlocker(self.pose_boxes[name]):
                self.pose_boxes[name].setValue(value)
        return self.pose_figures()

    def pose_figures(self) -> dict[str, float]:
        """The figures Fold, Curl, Roll and Twist show."""
        return {name: float(box.value()) for name, box in self.pose_boxes.items()}

    def show_edited(self, edited: bool, poseable: bool = True, scan_open: bool = True) -> None:
        """Say whether the open form was edited since it was made (its pose terms then bend it,
        the others wait for a shape picked); the pose terms are off for a leaf they cannot bend
        (a scan bent by its sheet: the scan open, or a project saved from it), and say why."""
        for name, box in self.pose_boxes.items():
            box.setEnabled(poseable)
            box.setToolTip(RELIEF[name] if poseable else sheet_tip(scan_open))
        if edited != self._edited:
            self._edited = edited
            self._describe()

    def show_pose_note(self, text: str) -> None:
        """A note under Fold, Curl and Wave on the chosen pose (none: hidden)."""
        self.pose_note.setText(text[:1].upper() + text[1:])
        self.pose_note.setVisible(bool(text))

    # --- widgets -------------------------------------------------------------------------------
    def _combo(self, items: tuple[str, ...], kind: str) -> QComboBox:
        box = QComboBox()
        box.addItems(list(items))
        for i, name in enumerate(items):
            if not name.startswith("("):
                box.setItemData(i, definition(name, kind), Qt.ItemDataRole.ToolTipRole)
        box.currentIndexChanged.connect(lambda _: self._changed())
        return box

    def _spin(self, box, low, high, value, tip: str, suffix: str = "", step: float = 1):
        box.setRange(low, high)
        box.setValue(value)
        box.setToolTip(tip)
        if suffix:
            box.setSuffix(suffix)
        box.setSingleStep(step)
        if isinstance(box, QDoubleSpinBox):
            box.setDecimals(3)
        box.valueChanged.connect(lambda _: self._changed())
        return box

    # --- state ---------------------------------------------------------------------------------
    def shape(self) -> str:
        item = self.gallery.currentItem()
        return item.data(Qt.ItemDataRole.UserRole) if item is not None else "ovate"

    def show_shape(self, shape: str | None) -> None:
        """Highlight the open form's `shape`, or nothing (None: the leaf open is not a form),
        choosing nothing: the gallery follows the document."""
        row = list(SHAPES).index(shape) if shape in SHAPES else -1
        if row != self.gallery.currentRow():
            with QSignalBlocker(self.gallery):
                self.gallery.setCurrentRow(row)
            if row >= 0:
                self.gallery.scrollToItem(self.gallery.item(row))
            self._describe()

    def form(self) -> Form:
        """The form the choosers describe (terms that do not apply are left out)."""
        shape = self.shape()
        margin = self.margin.currentText()
        fixed = SHAPES[shape].fixed_base
        base = None if fixed or self.base.currentIndex() == 0 else self.base.currentText()
        return Form(
            shape,
            apex=None if self.apex.currentIndex() == 0 else self.apex.currentText(),
            base=base,
            margin=margin,
            teeth=self.teeth.value() if margin in TOOTHED else None,
            lobes=self.lobes.value() if margin == "lobed" else None,
            venation=None if self.venation.currentIndex() == 0 else self.venation.currentText(),
            fold=self.fold.value(),
            curl=self.curl.value(),
            roll=self.roll.value(),
            twist=self.twist.value(),
            wave=self.wave.value(),
            seed=self.seed.value(),
        )

    def _describe(self) -> None:
        form_ = self.form()
        self.shape_text.setText(
            f"<b>{form_.shape}</b>: {definition(form_.shape)}" + (EDITED if self._edited else "")
            if self.gallery.currentItem() is not None
            else "The leaf open is not a form: Fold, Curl, Roll and Twist bend it; pick a shape "
            "to make a form."
        )
        self.texts["Apex"].setText(f"{form_.apex_term}: {definition(form_.apex_term, 'apex')}")
        fixed = SHAPES[form_.shape].fixed_base
        self.base.setEnabled(not fixed)
        base_text = f"{form_.base_term}: {definition(form_.base_term, 'base')}"
        self.texts["Base"].setText(base_text + (" (part of this shape)" if fixed else ""))
        self.texts["Margin"].setText(definition(form_.margin))
        self.teeth.setEnabled(form_.margin in TOOTHED)
        self.lobes.setEnabled(form_.margin == "lobed")
        self.texts["Teeth"].setText(RELIEF["teeth"])
        self.texts["Lobes"].setText(RELIEF["lobes"])
        venation = form_.venation_term
        self.texts["Venation"].setText(f"{venation}: {definition(venation, 'venation')}")
        for name in ("Fold", "Curl", "Roll", "Wave"):
            self.texts[name].setText(RELIEF[name.lower()])

    def _changed(self, picked: bool = False) -> None:
        self._picked = self._picked or picked
        self._describe()
        self._timer.start()

    def _emit(self) -> None:
        picked, self._picked = self._picked, False
        self.chosen.emit(self.form(), picked)

    def change_due(self) -> bool:  # a change of the terms waits to be emitted (debounced)
        return self._timer.isActive()

    def choose_now(self) -> None:
        """Emit the current form at once, as picked (tests, and the gallery's double click)."""
        self._timer.stop()
        self._picked = True
        self._emit()


def install(window, dock_area=Qt.DockWidgetArea.RightDockWidgetArea) -> FormsPanel:
    """Add the Forms dock to the main window (below the Sketch dock, both in sight at a first
    start as in the README's picture; a saved layout is restored over it): a chosen form
    becomes the document through the window's session (one undo step); Grow veins edits the
    current sketch (one undo step); the pose terms follow the document (form_documents.py).
    Also View > Compare forms and Help > Glossary of leaf terms (compare_view.py,
    glossary_view.py). Returns the dock's panel."""
    panel = FormsPanel()
    # the gallery's veins grow off the main thread once the first leaf is on screen (or could
    # not be): started with the window, they held up its first result by 0.5-1 s (the GIL)
    for shown in (window.result_shown, window.failure_shown):
        shown.connect(lambda *_: panel.grow_veins(window.worker.start))
    session = window.session
    gallery = GalleryForms()  # the documents the gallery made, and whether they were edited
    # the pose the dock's Fold, Curl, Roll and Twist show (the document's), and their figures
    dock_pose: dict[str, Any] = {"shown": (Pose(), {})}
    # the last blade grown (its form without a pose, the blade, its side-on note), and the form
    # waiting for its blade: a blade grows on a lane (60-100 ms, the main thread's before), and
    # a pose slider's change only poses the last one (a few ms)
    kept: dict[str, tuple[Form, Leaf, str, Sketch]] = {}
    # "form": the form to show once its blade has grown, "job": the growth, "serial": the
    # document open when it was chosen (another one opened meanwhile is not replaced)
    waiting: dict[str, Any] = {}

    def show(form: Form) -> None:
        _unposed, blade, side_on, sketch = kept["blade"]
        panel.show_pose_note("; ".join(note for note in (side_on, form.seam_note()) if note))
        session.new_document(form.leaf(blade), sketch, f"{form.shape} form")
        gallery.record(session.state, form.shape)
        panel.show_shape(form.shape)

    def follow(state, reason: str) -> None:
        """The gallery highlights the open document's shape, if the gallery made it, and the
        pose terms show its pose (not while a form chosen is on its way, or a change waits)."""
        if reason in ("document", "undo", "fallback"):
            panel.show_shape(gallery.shape(state))
        if reason in ("params", "saved") or "form" in waiting or panel.change_due():
            return
        poseable = can_pose(state.leaf)
        edited, scan_open = gallery.edited(state), state.scan is not None
        panel.show_edited(edited, poseable or state.leaf is None, scan_open)
        if poseable or state.leaf is not None:
            # a scan bent by its sheet has no pose (session.pose is flat): the boxes are cleared.
            # Kept, the last form's fold of 45 read on the boxes that were off, and the next
            # shape picked came in folded 45 (session 31)
            pose = session.pose
            figures = panel.show_pose(pose_terms(pose, session.half_width if poseable else 1.0))
            dock_pose["shown"] = (pose, figures)

    def grown(blade: tuple[Form, Leaf, str, Sketch]) -> None:
        kept["blade"] = blade
        form = waiting.get("form")
        if form is not None and form.unposed() == blade[0]:
            serial = waiting.pop("serial")
            waiting.clear()  # before the document: the dock's pose then follows it
            if session.state.serial == serial:
                show(form)

    def failed(unposed: Form, exc: BaseException) -> None:
        form = waiting.get("form")
        if form is not None and form.unposed() == unposed:
            waiting.clear()
            panel.show_shape(gallery.shape(session.state))  # the picked shape was not made
            window.show_error("Forms", describe(exc))

    def choose(form: Form, picked: bool) -> None:
        growing = waiting.get("form")
        if growing is None and gallery.action(session.state, picked) == "bend":
            # an edited form, or another leaf: the pose terms bend it (its other terms are kept
            # for the next shape picked), one undo step as the Parameters panel's sliders
            pose = terms_pose(panel.pose_figures(), session.half_width, dock_pose["shown"])
            # refused past the limits, with a message; a roll eased off its seam said
            bend_leaf(window, pose, final=True, say=panel.show_pose_note)
            return
        if not picked and growing is not None and session.state.serial != waiting["serial"]:
            return  # another document opened while the form chosen grows: it is not replaced
        unposed = form.unposed()
        if "blade" in kept and kept["blade"][0] == unposed:
            if "job" in waiting:
                waiting["job"].cancel()  # another form's blade, no longer wanted
            waiting.clear()
            show(form)
        elif growing is not None and growing.unposed() == unposed:
            waiting["form"] = form  # its blade is on its way: a pose change needs no other
        else:
            job = window.worker.start(FORM, grow_blade, form)
            job.on_done(grown).on_failed(partial(failed, unposed))
            waiting.update(form=form, job=job, serial=session.state.serial)

    def grow(venation: str) -> None:
        sketch = session.editable_sketch()
        if sketch is None:
            leaf = session.leaf
            if leaf is None:
                window.show_error("Grow veins", "There is no outline to grow veins in.")
                return
            sketch = outline_sketch(session.result, leaf)
        if sketch is None or len(sketch.boundary) < 3:
            window.show_error("Grow veins", "Draw an outline first (at least 3 points).")
            return
        base = None
        leaf = session.leaf
        midrib = blade_midrib(leaf) if leaf is not None else None  # base first, on the blade
        if not (sketch.veins and len(sketch.veins[0])) and midrib is not None:
            base = sketch.frame.to_plane(midrib[:1])[0][0]  # the midrib's base
        try:
            grown = with_grown_veins(sketch, venation, panel.seed.value(), base)
        except Exception as exc:
            window.show_error("Grow veins", str(exc))
            return
        session.commit_sketch(grown, f"Grow {venation} veins")

    panel.chosen.connect(choose)
    session.state_changed.connect(follow)
    panel.grow.connect(grow)
    add_grow_row(window.editor, grow)
    window.add_dock("Forms", panel, dock_area)  # stacked below the Sketch dock
    window.compared = COMPARISONS[FIRST]  # the forms compared last (slides show them)
    window.add_actions(compare_actions() + glossary_actions())
    panel.compare_button.clicked.connect(window.actions["view.compare_forms"].trigger)
    return panel
