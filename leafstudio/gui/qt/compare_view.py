"""View > Compare forms and File > Export slides.

Compare forms: two or four forms side by side in one window, each with the terms in which they
differ and what those mean (ovate beside obovate, serrate beside dentate), as a class compares
them. The picture is render/forms_figure.compare_figure drawn at its slide size and shown
scaled to the window (fonts and leaves shrink together, never overlapping): the very figure the
slides write. A comparison is chosen from the lessons' list
(forms/glossary.COMPARISONS), then each form's shape, margin and venation can be changed; the
window keeps the forms last compared (`window.compared`).

Export slides: the lesson's steps on the shown leaf and the forms compared last
(render/step_slides.py), as `leafstudio slides --compare` writes them, the leaf turned as the
lesson shows it (a drawn leaf at the angle it was drawn: gui/qt/lesson_view.py).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PySide6.QtCore import Qt
from PySide6.QtGui import QImage, QPixmap
from PySide6.QtWidgets import (
    QApplication,
    QComboBox,
    QDialog,
    QFileDialog,
    QGridLayout,
    QHBoxLayout,
    QLabel,
    QSizePolicy,
    QVBoxLayout,
)

from leafstudio.errors import LeafError
from leafstudio.forms import SHAPES, VENATION_KINDS, Form
from leafstudio.forms.glossary import COMPARISONS, compared_terms
from leafstudio.forms.terms import MARGINS
from leafstudio.gui.qt.actions import Action, show_once
from leafstudio.render.step_slides import plan_frame

USUAL = "(usual)"  # a venation chooser's entry for the shape's usual one (Form.venation None)
CHOOSERS = (
    ("shape", tuple(SHAPES)),
    ("margin", tuple(MARGINS)),
    ("venation", (USUAL, *VENATION_KINDS)),
)
FIRST = "ovate beside obovate"
PDF_FILTER, FOLDER_FILTER = "PDF (*.pdf)", "A folder: a PNG per slide and lesson.pdf (*)"


class CompareDialog(QDialog):
    """The comparison chooser, a row of term choosers per form, and the figure."""

    def __init__(self, window) -> None:
        super().__init__(window)
        self.setWindowTitle("Compare forms")
        self.window_ = window
        self.preset = QComboBox()
        self.preset.addItems(list(COMPARISONS))
        self.preset.setToolTip("Forms a lesson sets side by side; change any term below.")
        self.choosers = QGridLayout()
        self.boxes: list[dict[str, QComboBox]] = []
        self.note = QLabel()
        self.note.setStyleSheet("color: #b00020;")
        self.figure = None  # the matplotlib Figure shown
        self.picture = FittedPicture()
        top = QHBoxLayout()
        top.addWidget(QLabel("Compare"))
        top.addWidget(self.preset, 1)
        self.column = QVBoxLayout(self)
        self.column.addLayout(top)
        self.column.addLayout(self.choosers)
        self.column.addWidget(self.note)
        self.column.addWidget(self.picture, 1)
        self.preset.currentTextChanged.connect(self.set_forms)
        self.resize(1100, 720)
        self.set_forms(FIRST)
        self.preset.setCurrentText(FIRST)

    def forms(self) -> tuple[Form, ...]:
        """The forms shown, as their choosers say."""
        forms = []
        for form, boxes in zip(self.window_.compared, self.boxes, strict=True):
            terms = {kind: boxes[kind].currentText() for kind, _ in CHOOSERS}
            terms["venation"] = None if terms["venation"] == USUAL else terms["venation"]
            if terms["margin"] != form.margin:  # the count of teeth or lobes: the new margin's
                terms.update(teeth=None, lobes=None)
            forms.append(form.with_(**terms))
        return tuple(forms)

    def set_forms(self, name: str) -> None:
        """Show the comparison `name` of COMPARISONS, its choosers set to its forms."""
        forms = COMPARISONS[name]
        while self.choosers.count():
            item = self.choosers.takeAt(0)
            if item.widget() is not None:
                item.widget().deleteLater()
        self.boxes = []
        for row, (kind, _terms) in enumerate(CHOOSERS):
            self.choosers.addWidget(QLabel(kind.capitalize()), row, 0)
        for column, form in enumerate(forms, start=1):
            boxes = {}
            for row, (kind, terms) in enumerate(CHOOSERS):
                box = QComboBox()
                box.addItems(list(terms))
                box.setCurrentText(getattr(form, kind) or USUAL)
                box.setToolTip(f"The {kind} of form {column}")
                box.currentTextChanged.connect(lambda _t: self.redraw(self.forms()))
                self.choosers.addWidget(box, row, column)
                boxes[kind] = box
            self.boxes.append(boxes)
        self.redraw(forms)

    def redraw(self, forms: tuple[Form, ...]) -> None:
        """Draw `forms` side by side; a form the terms cannot make is said, the last kept."""
        from leafstudio.render.forms_figure import compare_figure

        QApplication.setOverrideCursor(Qt.CursorShape.WaitCursor)
        try:
            figure = compare_figure(forms)
        except LeafError as exc:
            self.note.setText(str(exc))
            return
        finally:
            QApplication.restoreOverrideCursor()
        self.note.setText("")
        self.window_.compared = forms
        self.figure = figure
        self.picture.set_image(figure_image(figure))


def figure_image(figure) -> QImage:
    """A matplotlib Figure drawn at its own size (Agg) as a QImage."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg  # heavy: when shown

    canvas = FigureCanvasAgg(figure)
    canvas.draw()
    rgba = np.asarray(canvas.buffer_rgba())
    height, width = rgba.shape[:2]
    return QImage(rgba.tobytes(), width, height, 4 * width, QImage.Format.Format_RGBA8888).copy()


class FittedPicture(QLabel):
    """An image scaled to fit the label, its proportions kept."""

    def __init__(self) -> None:
        super().__init__()
        self.image = QImage()
        self.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.setMinimumSize(320, 180)
        self.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Ignored)

    def set_image(self, image: QImage) -> None:
        self.image = image
        self._fit()

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        self._fit()

    def _fit(self) -> None:
        if not self.image.isNull():
            size = self.size() * self.devicePixelRatioF()
            scaled = self.image.scaled(
                size, Qt.AspectRatioMode.KeepAspectRatio, Qt.TransformationMode.SmoothTransformation
            )
            scaled.setDevicePixelRatio(self.devicePixelRatioF())
            self.setPixmap(QPixmap.fromImage(scaled))


def comparison_title(forms: tuple[Form, ...]) -> str:
    """ "ovate beside obovate": the first term each form differs in, joined."""
    return " beside ".join(terms[0][1] for terms in compared_terms(forms))


def export_slides(window, path: str):
    """Start writing the lesson's steps on the shown leaf and the forms compared last as slides
    to `path` (a .pdf, or a folder: a PNG per slide and lesson.pdf) in the background, as the
    other exports (exports.py); the job's handle, or None when there is no leaf (an error box
    says so)."""
    from leafstudio.gui.model.exports import slides

    result = window.session.result
    if result is None:
        window.show_error("Nothing to export", "There is no reconstructed leaf yet.")
        return None
    compared = [(comparison_title(window.compared), window.compared)]
    frame = plan_frame(result, window.session.view_frame())  # the lesson's: a drawn leaf as drawn
    return window.run_export(Path(path).name, slides, result, compared, path, frame=frame)


def _ask_slides(window) -> None:
    path, chosen = QFileDialog.getSaveFileName(
        window, "Export slides", "lesson.pdf", f"{PDF_FILTER};;{FOLDER_FILTER}"
    )
    if path:
        if chosen == PDF_FILTER and not path.lower().endswith(".pdf"):
            path += ".pdf"
        export_slides(window, path)


def compare_actions() -> tuple[Action, ...]:
    """File > Export slides and View > Compare forms, as rows of the window's action table."""
    return (
        Action(
            "file.export_slides",
            "File",
            "Export s&lides…",
            _ask_slides,
            tip="The lesson's steps on this leaf and the forms compared last, as slides: "
            "a PDF, or a folder of PNGs with the PDF",
            before="file.quit",
        ),
        Action(
            "view.compare_forms",
            "View",
            "Compare &forms…",
            show_once(CompareDialog),
            tooltip="Two or four forms side by side, with the terms in which they differ.",
            separator=True,
        ),
    )
