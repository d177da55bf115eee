"""A leaf seen from above as a small picture, with QPainter: the gallery's thumbnails
(forms_dock.py) and the glossary's pictures (glossary_view.py)."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, Qt
from PySide6.QtGui import QColor, QImage, QPainter, QPainterPath, QPen


def draw_plane(
    outline: np.ndarray,
    veins: list[np.ndarray] | tuple[np.ndarray, ...],
    size: int,
    box: np.ndarray | None = None,
    sit: bool = False,
) -> QImage:
    """An (n, 2) outline filled and (m, 2) veins drawn over it, in a `size` square showing
    `box` (x0, y0, x1, y1 of the plane; default the outline's bounds), what lies outside cut
    off; `sit`: resting on the square's lower edge rather than centred."""
    image = QImage(size, size, QImage.Format.Format_ARGB32_Premultiplied)
    image.fill(Qt.GlobalColor.transparent)
    lo, hi = (outline.min(axis=0), outline.max(axis=0)) if box is None else (box[:2], box[2:])
    scale = 0.9 * size / max(float((hi - lo).max()), 1e-12)
    centre = (lo + hi) / 2
    middle = 0.98 * size - (hi - lo)[1] * scale / 2 if sit else size / 2  # the centre's row

    def point(p: np.ndarray) -> QPointF:
        q = (p[:2] - centre) * scale
        return QPointF(size / 2 + q[0], middle - q[1])

    painter = QPainter(image)
    painter.setRenderHint(QPainter.RenderHint.Antialiasing)
    path = QPainterPath(point(outline[0]))
    for p in outline[1:]:
        path.lineTo(point(p))
    path.closeSubpath()
    painter.setPen(QPen(QColor("#2f5d1e"), 1.2))
    painter.setBrush(QColor("#8cc46a"))
    painter.drawPath(path)
    painter.setPen(QPen(QColor("#e9f5dc"), 0.9))
    painter.setBrush(Qt.BrushStyle.NoBrush)
    for vein in veins:
        line = QPainterPath(point(vein[0]))
        for p in vein[1:]:
            line.lineTo(point(p))
        painter.drawPath(line)
    painter.end()
    return image
