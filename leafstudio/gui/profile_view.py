"""A small side view of the chosen vein: its height along its length, with handles to drag.

x runs along the vein from its base (left) to its tip (right), y is the height above the leaf's
plane (the dashed line). The vein's own curve and points are drawn in its colour; the profile
(gui/vein_profile.py) is the thin line through the square handles. Dragging a handle reshapes
the profile and every point of the vein takes its height from it, live; a drag is one undo step
(the editor turns `dragged` into previews and `released` into one commit). Colours follow the
palette; sizes are in logical pixels, so they follow the device pixel ratio.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, QRectF, QSize, Qt, Signal
from PySide6.QtGui import QColor, QMouseEvent, QPainter, QPainterPath, QPaintEvent, QPalette, QPen
from PySide6.QtWidgets import QSizePolicy, QWidget

from leafstudio.gui.layers import vein_color
from leafstudio.gui.sketch_model import Sketch, plane_arc_lengths
from leafstudio.gui.vein_profile import Profile

HANDLE_PIXELS = 9.0
HIT_PIXELS = 10.0
MARGINS = (10.0, 8.0, 10.0, 16.0)  # left, top, right, bottom (the bottom holds "base" and "tip")
PAD = 0.2  # share of the height range left above and below the drawn heights
SELECTED = "#ffd400"


class ProfileView(QWidget):
    """The side view; `set_vein(sketch, vein)` shows a vein (an index past the veins: none).

    Signals
    -------
    dragged(Sketch)
        The sketch with the vein's heights as the handle being dragged makes them.
    released(Sketch, Sketch)
        The sketch before the drag began and after it, once the handle is let go.
    """

    dragged = Signal(object)
    released = Signal(object, object)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.sketch = Sketch()
        self.vein = -1
        self.profile: Profile | None = None
        self.grabbed: int | None = None  # the handle being dragged
        self._before: Sketch | None = None
        self._range: tuple[float, float] | None = None  # heights shown; held during a drag
        self.setMinimumHeight(96)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        self.setMouseTracking(True)  # the cursor shows where a handle can be grabbed
        self.setToolTip(
            "The chosen vein's height along it, from its base (left) to its tip (right); the "
            "dashed line is the leaf's plane. Drag a square handle to reshape the whole vein's "
            "heights at once (one undo step per drag)."
        )

    def sizeHint(self) -> QSize:
        return QSize(320, 120)

    # --- model ---------------------------------------------------------------------------------
    def set_vein(self, sketch: Sketch, vein: int) -> None:
        """Show vein `vein` of `sketch`. The handles are kept while the profile still gives the
        vein's heights (after the view's own drag, a redo of it); otherwise they are made anew
        from the vein (another vein, an undo, a height typed in)."""
        same = vein == self.vein and self.profile is not None
        self.sketch, self.vein = sketch, vein
        if not self.has_vein():
            self.profile = None
        elif self.grabbed is None:
            fractions, heights = self._vein_shares()
            tolerance = 1e-9 * sketch.extent()
            if not (same and self.profile.fits(fractions, heights, tolerance)):
                self.profile = Profile.of_vein(fractions, heights)
            self._range = None
        self.update()

    def has_vein(self) -> bool:
        return 0 <= self.vein < len(self.sketch.veins)

    def _vein_shares(self) -> tuple[np.ndarray, np.ndarray]:
        return self.sketch.vein_fractions(self.vein), self.sketch.veins[self.vein][:, 2]

    # --- geometry ------------------------------------------------------------------------------
    def _plot(self) -> QRectF:
        left, top, right, bottom = MARGINS
        return QRectF(
            left, top, max(self.width() - left - right, 1), max(self.height() - top - bottom, 1)
        )

    def _heights_range(self) -> tuple[float, float]:
        if self._range is not None:
            return self._range
        values = [0.0]
        if self.has_vein():
            values += list(self.sketch.vein_curve(self.vein)[:, 2])
        if self.profile is not None:
            values += list(self.profile.h)
        lo, hi = min(values), max(values)
        pad = max(PAD * (hi - lo), 0.02 * self.sketch.extent())
        return lo - pad, hi + pad

    def to_view(self, t: float, h: float) -> QPointF:
        """Widget position of share `t` of the vein's length at height `h`."""
        plot, (lo, hi) = self._plot(), self._heights_range()
        return QPointF(
            plot.left() + t * plot.width(), plot.bottom() - (h - lo) / (hi - lo) * plot.height()
        )

    def from_view(self, pos: QPointF) -> tuple[float, float]:
        """Share of the length and height at a widget position."""
        plot, (lo, hi) = self._plot(), self._heights_range()
        t = (pos.x() - plot.left()) / plot.width()
        return t, lo + (plot.bottom() - pos.y()) / plot.height() * (hi - lo)

    def handle_at(self, pos: QPointF) -> int | None:
        """The handle under a widget position, if any."""
        if self.profile is None:
            return None
        spots = [self.to_view(t, h) for t, h in zip(self.profile.t, self.profile.h, strict=True)]
        d = [float(np.hypot(p.x() - pos.x(), p.y() - pos.y())) for p in spots]
        best = int(np.argmin(d))
        return best if d[best] <= HIT_PIXELS else None

    # --- drawing -------------------------------------------------------------------------------
    def paintEvent(self, event: QPaintEvent) -> None:
        palette = self.palette()
        painter = QPainter(self)
        painter.setRenderHint(QPainter.RenderHint.Antialiasing)
        painter.fillRect(self.rect(), palette.color(QPalette.ColorRole.Base))
        ink = palette.color(QPalette.ColorRole.Text)
        faint = palette.color(QPalette.ColorRole.PlaceholderText)
        plot = self._plot()
        painter.setPen(QPen(faint, 1))
        painter.drawRect(plot)
        painter.drawText(
            QRectF(plot.left(), plot.bottom(), plot.width(), MARGINS[3]),
            Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter,
            "base",
        )
        painter.drawText(
            QRectF(plot.left(), plot.bottom(), plot.width(), MARGINS[3]),
            Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter,
            "tip",
        )
        if not self.has_vein() or self.profile is None:
            painter.drawText(plot, Qt.AlignmentFlag.AlignCenter, "Choose a vein to see its heights")
            return
        plane = QPen(faint, 1, Qt.PenStyle.DashLine)
        painter.setPen(plane)
        painter.drawLine(self.to_view(0, 0), self.to_view(1, 0))
        color = QColor(vein_color(self.vein))
        curve = self.sketch.vein_curve(self.vein)
        arc = plane_arc_lengths(curve)
        shares = arc / arc[-1] if arc[-1] > 0 else np.zeros(len(arc))
        painter.setPen(QPen(color, 2))
        painter.drawPath(self._path(shares, curve[:, 2]))
        t = np.linspace(0, 1, 64)
        painter.setPen(QPen(ink, 1))
        painter.drawPath(self._path(t, self.profile.heights(t)))
        painter.setBrush(color)
        painter.setPen(Qt.PenStyle.NoPen)
        for share, h in zip(*self._vein_shares(), strict=True):
            painter.drawEllipse(self.to_view(share, h), 3.0, 3.0)
        peak = float(curve[np.argmax(np.abs(curve[:, 2])), 2])  # farthest from the plane
        painter.setPen(QPen(faint, 1))
        painter.drawText(
            plot.adjusted(4, 2, -4, -2),
            Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop,
            f"peak {peak:.3g}",
        )
        painter.setPen(QPen(ink, 1.5))
        r = HANDLE_PIXELS / 2
        for i, (share, h) in enumerate(zip(self.profile.t, self.profile.h, strict=True)):
            painter.setBrush(
                QColor(SELECTED if i == self.grabbed else palette.color(QPalette.ColorRole.Base))
            )
            spot = self.to_view(share, h)
            painter.drawRect(QRectF(spot.x() - r, spot.y() - r, 2 * r, 2 * r))

    def _path(self, t: np.ndarray, h: np.ndarray) -> QPainterPath:
        path = QPainterPath(self.to_view(float(t[0]), float(h[0])))
        for share, height in zip(t[1:], h[1:], strict=True):
            path.lineTo(self.to_view(float(share), float(height)))
        return path

    # --- dragging ------------------------------------------------------------------------------
    def mousePressEvent(self, event: QMouseEvent) -> None:
        if event.button() != Qt.MouseButton.LeftButton:
            super().mousePressEvent(event)
            return
        self.grabbed = self.handle_at(event.position())
        if self.grabbed is not None:
            self._range = self._heights_range()  # the scale holds still under the hand
            self._before = self.sketch
            self.update()

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        if self.grabbed is None or self.profile is None:
            over = self.handle_at(event.position()) is not None
            self.setCursor(Qt.CursorShape.SizeAllCursor if over else Qt.CursorShape.ArrowCursor)
            super().mouseMoveEvent(event)
            return
        t, h = self.from_view(event.position())
        self.profile = self.profile.moved(self.grabbed, t, h)
        fractions = self.sketch.vein_fractions(self.vein)
        self.sketch = self.sketch.with_heights(self.vein, self.profile.heights(fractions))
        self.update()
        self.dragged.emit(self.sketch)

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        before, after = self._before, self.sketch
        self.grabbed, self._before, self._range = None, None, None
        self.update()
        if before is not None and after is not before:
            self.released.emit(before, after)
        super().mouseReleaseEvent(event)
