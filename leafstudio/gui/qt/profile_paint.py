"""How the vein's side view (profile_view.py) draws itself: the plot's frame and ends, the vein's
line, its control points and handles, or the boundary's heights once round it. A mixin of
ProfileView, which holds the state it draws.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QRectF, Qt
from PySide6.QtGui import (
    QColor,
    QPainter,
    QPainterPath,
    QPaintEvent,
    QPalette,
    QPen,
)

from leafstudio.gui.model.form_sketch import FLAT
from leafstudio.gui.model.layers import BOUNDARY_COLOR, vein_color
from leafstudio.gui.model.vein_profile import end_words
from leafstudio.gui.qt.leaf_picture import polyline_path

HANDLE_PIXELS = 9.0
MARGINS = (10.0, 8.0, 10.0, 16.0)  # left, top, right, bottom (the bottom holds "base" and "tip")
SELECTED = "#ffd400"  # the selected handle's fill, as the sketch's selected point


class ProfilePainting:
    """paintEvent and its parts, for ProfileView."""

    def paintEvent(self, event: QPaintEvent) -> None:
        palette = self.palette()
        painter = QPainter(self)
        painter.setRenderHint(QPainter.RenderHint.Antialiasing)
        painter.fillRect(self.rect(), palette.color(QPalette.ColorRole.Base))
        ink = palette.color(QPalette.ColorRole.Text)
        faint = palette.color(QPalette.ColorRole.PlaceholderText)
        focus = palette.color(QPalette.ColorRole.Highlight)
        plot = self._plot()
        painter.setPen(QPen(focus, 1.5) if self.hasFocus() else QPen(faint, 1))
        painter.drawRect(plot)
        painter.setPen(QPen(faint, 1))
        below = QRectF(plot.left(), plot.bottom(), plot.width(), MARGINS[3])
        ends = end_words(self.sketch, self.vein)
        sides = (Qt.AlignmentFlag.AlignLeft, Qt.AlignmentFlag.AlignRight)
        for align, text in zip(sides, ends, strict=True):
            painter.drawText(below, align | Qt.AlignmentFlag.AlignVCenter, text)
        if self.has_boundary():
            self._draw_boundary(painter, palette)
            return
        if not self.has_vein() or self.profile is None:
            painter.drawText(plot, Qt.AlignmentFlag.AlignCenter, "Choose a vein to see its heights")
            return
        painter.setPen(QPen(faint, 1, Qt.PenStyle.DashLine))
        painter.drawLine(self.to_view(0, 0), self.to_view(1, 0))
        color = QColor(vein_color(self.vein))
        shares, heights = self._line()
        painter.setPen(QPen(color, 2))
        painter.drawPath(self._path(shares, heights))
        t = np.linspace(0, 1, 128)
        painter.setPen(QPen(ink, 1))
        painter.drawPath(self._path(t, self.profile.heights(t)))
        self._draw_points(painter, color, *self._vein_shares())
        peak = float(heights[np.argmax(np.abs(heights))])  # farthest from the plane
        painter.setPen(QPen(faint, 1))
        painter.drawText(
            plot.adjusted(4, 2, -4, -2),
            Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop,
            f"peak {peak:.3g}",
        )
        self._draw_handles(painter, palette)

    def _draw_points(self, painter: QPainter, color: QColor, t: np.ndarray, h: np.ndarray) -> None:
        """The control points, as dots in the curve's colour."""
        painter.setBrush(color)
        painter.setPen(Qt.PenStyle.NoPen)
        for share, height in zip(t, h, strict=True):
            painter.drawEllipse(self.to_view(share, height), 3.0, 3.0)

    def _draw_boundary(self, painter: QPainter, palette: QPalette) -> None:
        """The boundary's heights once round it (read only: they come from a loaded leaf's
        relief, and a drawn leaf's boundary lies on the plane)."""
        shares, heights, points = self._outline
        faint = palette.color(QPalette.ColorRole.PlaceholderText)
        painter.setPen(QPen(faint, 1, Qt.PenStyle.DashLine))
        painter.drawLine(self.to_view(0, 0), self.to_view(1, 0))
        base = palette.color(QPalette.ColorRole.Base)
        color = QColor(
            BOUNDARY_COLOR if base.lightnessF() >= 0.5 else palette.color(QPalette.ColorRole.Text)
        )
        painter.setPen(QPen(color, 2))
        painter.drawPath(self._path(shares, heights))
        self._draw_points(painter, color, points, np.interp(points, shares, heights))
        painter.setPen(QPen(faint, 1))
        painter.drawText(
            self._plot().adjusted(4, 2, -4, -2),
            Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop,
            self.boundary_caption(),
        )

    def boundary_caption(self) -> str:
        """What the boundary's side view says over its line: where its heights come from (a
        loaded leaf's relief: a file, scan, demo or form; a drawn leaf's lies on the plane)."""
        if not len(self.sketch.relief):
            return "boundary: on the plane (a drawn leaf's boundary has no heights)"
        heights = self._outline[1]
        peak = float(heights[np.argmax(np.abs(heights))]) if len(heights) else 0.0
        extent = float(np.ptp(self.sketch.boundary, axis=0).max()) if len(heights) else 0.0
        if abs(peak) <= FLAT * extent:  # a posed form's blade laid flat: 4.8e-17, round-off
            peak = 0.0
        return f"boundary, as loaded: peak {peak:.3g} (not editable)"

    def _draw_handles(self, painter: QPainter, palette: QPalette) -> None:
        """Square handles; the selected (or grabbed) one larger and filled, with a ring in the
        palette's highlight while the view has the keyboard focus."""
        ink = palette.color(QPalette.ColorRole.Text)
        for i, (share, h) in enumerate(zip(self.profile.t, self.profile.h, strict=True)):
            spot = self.to_view(share, h)
            chosen = i in (self.selected, self.grabbed)
            r = HANDLE_PIXELS / 2 + (1.5 if chosen else 0.0)
            painter.setPen(QPen(ink, 1.5))
            painter.setBrush(QColor(SELECTED) if chosen else palette.color(QPalette.ColorRole.Base))
            painter.drawRect(QRectF(spot.x() - r, spot.y() - r, 2 * r, 2 * r))
            if chosen and self.hasFocus():
                ring = r + 3.0
                painter.setPen(QPen(palette.color(QPalette.ColorRole.Highlight), 2))
                painter.setBrush(Qt.BrushStyle.NoBrush)
                painter.drawRect(QRectF(spot.x() - ring, spot.y() - ring, 2 * ring, 2 * ring))

    def _path(self, t: np.ndarray, h: np.ndarray) -> QPainterPath:
        """The line through shares `t` of the length at heights `h` (view_xy, for all at
        once: a point at a time cost 6-13 ms of a new document's paint, issue 24)."""
        x, y = self.view_xy(np.asarray(t, dtype=float), np.asarray(h, dtype=float))
        return polyline_path(np.column_stack([x, y]))
