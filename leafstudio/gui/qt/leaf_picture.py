"""A leaf seen from above as a small picture, with QPainter: the gallery's thumbnails
(forms_dock.py) and the glossary's pictures (glossary_view.py); and polylines as painter paths
made whole by numpy (the sketch and its side view draw theirs with it)."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QByteArray, QDataStream, Qt
from PySide6.QtGui import QColor, QImage, QPainter, QPainterPath, QPen

PATH_ELEMENT = np.dtype([("type", ">i4"), ("x", ">f8"), ("y", ">f8")])  # as QDataStream has it


def polyline_path(xy: np.ndarray, closed: bool = False) -> QPainterPath:
    """A path through (n, 2+) points (x, y as given), read from the bytes QDataStream writes for
    a path (a move, then lines; no start, the winding fill): built whole by numpy, where a
    lineTo per point cost 1.3-1.6 ms per 700 points (12 ms of a 2M-point scan's sketch)."""
    xy = np.asarray(xy, dtype=float)[:, :2]
    if closed:
        xy = np.vstack([xy, xy[:1]])  # as closeSubpath draws it
    elements = np.empty(len(xy), PATH_ELEMENT)
    elements["type"] = 1  # QPainterPath.ElementType.LineToElement
    elements["type"][0] = 0  # MoveToElement
    elements["x"], elements["y"] = xy[:, 0], xy[:, 1]
    data = b"".join((np.array([len(xy)], ">i4").tobytes(), elements.tobytes(), bytes(8)))
    path = QPainterPath()
    QDataStream(QByteArray(data)) >> path
    if closed:
        path.closeSubpath()
    return path


def draw_plane(
    outline: np.ndarray,
    veins: list[np.ndarray] | tuple[np.ndarray, ...],
    size: int | tuple[int, int],
    box: np.ndarray | None = None,
    sit: bool = False,
) -> QImage:
    """An (n, 2) outline filled and (m, 2) veins drawn over it, in a `size` square (or a
    (width, height) frame) showing `box` (x0, y0, x1, y1 of the plane; default the outline's
    bounds), what lies outside cut off; `sit`: resting on the frame's lower edge rather than
    centred."""
    width, height = (size, size) if isinstance(size, int) else size
    image = QImage(width, height, QImage.Format.Format_ARGB32_Premultiplied)
    image.fill(Qt.GlobalColor.transparent)
    lo, hi = (outline.min(axis=0), outline.max(axis=0)) if box is None else (box[:2], box[2:])
    span = np.maximum(hi - lo, 1e-12)
    scale = 0.9 * min(width / span[0], height / span[1])
    centre = (lo + hi) / 2
    middle = 0.98 * height - span[1] * scale / 2 if sit else height / 2  # the centre's row

    def picture(points: np.ndarray) -> np.ndarray:
        q = (np.asarray(points, dtype=float)[:, :2] - centre) * scale
        return np.column_stack([width / 2 + q[:, 0], middle - q[:, 1]])

    painter = QPainter(image)
    painter.setRenderHint(QPainter.RenderHint.Antialiasing)
    path = polyline_path(picture(outline), closed=True)
    painter.setPen(QPen(QColor("#2f5d1e"), 1.2))
    painter.setBrush(QColor("#8cc46a"))
    painter.drawPath(path)
    painter.setPen(QPen(QColor("#e9f5dc"), 0.9))
    painter.setBrush(Qt.BrushStyle.NoBrush)
    for vein in veins:
        painter.drawPath(polyline_path(picture(vein)))
    painter.end()
    return image
