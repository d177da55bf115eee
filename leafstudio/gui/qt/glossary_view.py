"""Help > Glossary of leaf terms: every term a form is made from (shape, apex, base, margin,
venation) with a small picture and its definition in plain words.

The pictures come from the forms themselves (forms/glossary.term_picture: the leaf's tip for an
apex, its foot for a base, one side's middle for a margin, the whole leaf for a shape or a
venation), drawn once per term and size with QPainter and cached for the process; the dialog
draws them the first time it opens (about half a second for all), not at start-up.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import Qt, QTimer
from PySide6.QtGui import QImage, QPixmap, QResizeEvent
from PySide6.QtWidgets import (
    QDialog,
    QGridLayout,
    QLabel,
    QScrollArea,
    QVBoxLayout,
    QWidget,
)

from leafstudio.forms.glossary import PICTURED, term_picture
from leafstudio.forms.terms import definition
from leafstudio.gui.qt.actions import Action, show_once
from leafstudio.gui.qt.leaf_picture import draw_plane
from leafstudio.render.forms_figure import upright

PICTURE = 96  # pixels, the pictures' least size
PICTURE_SIZES = (96, 144, 192, 256)  # ... and those they grow to on a large dialog (a projector's
# class reads them from the back of the room): a fifth of its width and a quarter of its height
# at most, the words growing with them (by half at most)
RESIZE_MS = 120  # the pictures are redrawn this long after the last resize step
KIND_TITLES = {
    "shape": "Shapes: the blade's outline as a whole",
    "apex": "Apexes: the tip (its last quarter)",
    "base": "Bases: where the blade meets the stalk",
    "margin": "Margins: the blade's edge",
    "venation": "Venation: how the veins run",
}
_images: dict[tuple[str, str, int], QImage] = {}


def term_image(kind: str, term: str, size: int = PICTURE) -> QImage:
    """The term's picture in a `size` square, drawn once per term and size, then cached; the
    leaf stands apex up, as the definitions' 'lower' and 'above' and Compare forms have it."""
    key = (kind, term, size)
    if key not in _images:
        picture = term_picture(kind, term)
        x0, y0, x1, y1 = picture.box
        box = np.array([-y1, x0, -y0, x1])  # the plane's box turned as upright() turns it
        veins = [upright(v) for v in picture.veins]
        _images[key] = draw_plane(upright(picture.outline), veins, size, box=box)
    return _images[key]


class GlossaryDialog(QDialog):
    """Every pictured term, grouped by kind: its picture, its name and its definition."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Glossary of leaf terms")
        body = QWidget()
        grid = QGridLayout(body)
        grid.setColumnStretch(2, 1)
        self.pictures: dict[tuple[str, str], QLabel] = {}
        self._words: list[QLabel] = []  # the headings, each term's name and definition
        row = 0
        for kind, terms in PICTURED.items():
            heading = QLabel(f"<h3>{KIND_TITLES[kind]}</h3>")
            self._words.append(heading)
            grid.addWidget(heading, row, 0, 1, 3)
            row += 1
            for term in terms:
                picture = QLabel()
                picture.setAlignment(Qt.AlignmentFlag.AlignCenter)
                picture.setPixmap(QPixmap.fromImage(term_image(kind, term)))
                name = QLabel(f"<b>{term}</b>")
                text = QLabel(definition(term, kind))
                text.setWordWrap(True)
                self._words += [name, text]
                grid.addWidget(picture, row, 0)
                grid.addWidget(name, row, 1, Qt.AlignmentFlag.AlignVCenter)
                grid.addWidget(text, row, 2, Qt.AlignmentFlag.AlignVCenter)
                self.pictures[kind, term] = picture
                row += 1
        scroll = QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setWidget(body)
        column = QVBoxLayout(self)
        column.addWidget(scroll)
        self.picture_size = PICTURE
        self._resized = QTimer(self, singleShot=True, interval=RESIZE_MS)
        self._resized.timeout.connect(self._fit_pictures)
        self.resize(620, 640)

    def resizeEvent(self, event: QResizeEvent) -> None:
        super().resizeEvent(event)
        self._resized.start()  # a drag's every step would redraw every picture

    def _fit_pictures(self) -> None:
        """The pictures at the largest of PICTURE_SIZES within a fifth of the dialog's width
        and a quarter of its height, and the words grown with them."""
        fitting = [s for s in PICTURE_SIZES if 5 * s <= self.width() and 4 * s <= self.height()]
        size = max(fitting, default=PICTURE)
        if size == self.picture_size:
            return
        self.picture_size = size
        for (kind, term), label in self.pictures.items():
            label.setPixmap(QPixmap.fromImage(term_image(kind, term, size)))
        font = self.font()
        font.setPointSizeF(font.pointSizeF() * min(size / PICTURE, 1.5))
        for label in self._words:
            label.setFont(font)


def glossary_actions() -> tuple[Action, ...]:
    """Help > Glossary of leaf terms, as a row of the window's action table."""
    return (
        Action(
            "help.glossary",
            "Help",
            "&Glossary of leaf terms…",
            show_once(GlossaryDialog),
            tooltip="Every shape, apex, base, margin and venation term, drawn and defined.",
            before="help.about",
        ),
    )
