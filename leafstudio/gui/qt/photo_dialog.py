"""File > Open photo's dialog: the photo, the leaf's length, a ruler clicked on the photo and
the end the base is at (issue 23, item 6). What the fields and clicks mean is
gui/model/photo_import.py's; this shows the photo, draws the ruler and passes clicks (in the
photo's pixels) and text there.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, Qt
from PySide6.QtGui import QColor, QImage, QMouseEvent, QPainter, QPen, QPixmap
from PySide6.QtWidgets import (
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QFormLayout,
    QLabel,
    QLineEdit,
    QVBoxLayout,
    QWidget,
)

from leafstudio._shared.inputs import read_image
from leafstudio.errors import LeafError
from leafstudio.gui.model.photo_import import PhotoImport
from leafstudio.sources.photo import BASE_ENDS

SHOWN = (720, 480)  # the photo is shown at most this big, in screen pixels
RULER_COLOUR = QColor("#e0218a")


def photo_image(path: str) -> QImage:
    """The photo as the leaf is found in it (read_image: upright, its EXIF orientation applied,
    so a click's pixel is the finder's); a null image when it cannot be read (OK then says why)."""
    try:
        rgb = np.ascontiguousarray(read_image(path)[..., :3])
    except LeafError:
        return QImage()
    height, width = rgb.shape[:2]
    return QImage(rgb.tobytes(), width, height, 3 * width, QImage.Format.Format_RGB888).copy()


class PhotoPicture(QLabel):
    """The photo, scaled to fit, with the ruler drawn over it; a left click is the ruler's next
    end (PhotoImport.click), in the photo's pixels."""

    def __init__(self, model: PhotoImport, on_change, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model, self.on_change = model, on_change
        image = photo_image(model.path)
        self.photo = QPixmap.fromImage(image)
        if not self.photo.isNull():
            self.photo = self.photo.scaled(*SHOWN, Qt.AspectRatioMode.KeepAspectRatio,
                                           Qt.TransformationMode.SmoothTransformation)  # fmt: skip
        self.zoom = self.photo.width() / image.width() if image.width() else 1.0
        self.setFixedSize(self.photo.size())
        self.setCursor(Qt.CursorShape.CrossCursor)
        self.setToolTip("Click the two ends of a ruler (or anything of known length) in the photo")
        self.redraw()

    def to_photo(self, at: QPointF) -> tuple[float, float]:
        """A point on the picture, in the photo's pixels (column, row)."""
        return at.x() / self.zoom, at.y() / self.zoom

    def mousePressEvent(self, event: QMouseEvent) -> None:
        if event.button() == Qt.MouseButton.LeftButton and not self.photo.isNull():
            self.model.click(self.to_photo(event.position()))
            self.redraw()
            self.on_change()

    def redraw(self) -> None:
        """The photo with the ruler's ends and the line between them."""
        shown = QPixmap(self.photo)
        if not shown.isNull() and self.model.ruler:
            painter = QPainter(shown)
            painter.setRenderHint(QPainter.RenderHint.Antialiasing)
            painter.setPen(QPen(RULER_COLOUR, 2))
            ends = [QPointF(*(end * self.zoom)) for end in self.model.ruler]
            if len(ends) == 2:
                painter.drawLine(ends[0], ends[1])
            for end in ends:
                painter.drawEllipse(end, 4, 4)
            painter.end()
        self.setPixmap(shown)


class PhotoDialog(QDialog):
    """The photo, the leaf's length field, the ruler's distance field, the base's end and a line
    saying where the leaf's size and base come from; OK opens the photo with `model.options()`."""

    def __init__(self, model: PhotoImport, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.setWindowTitle("Open a photo of a leaf")
        self.picture = PhotoPicture(model, self.update_summary, self)
        self.length = QLineEdit(model.length)
        self.length.setPlaceholderText("8cm, 80mm, or empty")
        self.length.setToolTip(
            "The leaf's length, base to apex: with its unit (the leaf in millimetres, its real "
            "size in an export), a number in the leaf's own units, or empty"
        )
        self.distance = QLineEdit()
        self.distance.setPlaceholderText("10 mm")
        self.distance.setToolTip("The distance between the two points clicked on the photo")
        self.base_end = QComboBox()
        for end in BASE_ENDS:  # as `leafstudio photo --base-end`
            self.base_end.addItem("found in the photo" if end == "auto" else f"{end} end", end)
        self.base_end.setCurrentIndex(BASE_ENDS.index(model.base_end))
        self.base_end.setToolTip(
            "Where the leaf's base is in the photo: found from its petiole, a basal notch or the "
            "veins, else the wider end (an obovate leaf whose veins do not show: name its end)"
        )
        self.summary = QLabel()
        self.summary.setWordWrap(True)
        form = QFormLayout()
        form.addRow("Leaf length", self.length)
        form.addRow("Ruler distance", self.distance)
        form.addRow("Base", self.base_end)
        buttons = QDialogButtonBox(
            QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel
        )
        buttons.accepted.connect(self.try_accept)
        buttons.rejected.connect(self.reject)
        layout = QVBoxLayout(self)
        layout.addWidget(self.picture, alignment=Qt.AlignmentFlag.AlignCenter)
        layout.addLayout(form)
        layout.addWidget(self.summary)
        layout.addWidget(buttons)
        self.length.textChanged.connect(self.update_summary)
        self.distance.textChanged.connect(self.update_summary)
        self.base_end.currentIndexChanged.connect(self.update_summary)
        self.update_summary()

    def update_summary(self) -> None:
        """The fields into the model; the line below them says what they give."""
        self.model.length, self.model.distance = self.length.text(), self.distance.text()
        self.model.base_end = self.base_end.currentData()
        self.summary.setText(self.model.summary())
        self.summary.setStyleSheet("")

    def try_accept(self) -> None:
        """OK: accepted when the fields make sense, else the line says why in red."""
        self.update_summary()
        try:
            self.model.options()
        except LeafError as exc:
            self.summary.setText(f"Cannot open the photo: {exc}")
            self.summary.setStyleSheet("color: #b00020")
            return
        self.accept()
