"""The 2D sketch editor on the leaf plane: click, drag and delete control points of the boundary
(a closed spline) and of each vein (open splines), and set each vein point's height.

The editor never changes the document itself: it emits `preview(sketch)` while a point is dragged
(so the 3D view follows) and `committed(before, after, text)` when an edit is done; the main window
turns the latter into an undoable command and hands the sketch back with `set_sketch`.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, Qt, Signal
from PySide6.QtGui import (
    QBrush,
    QColor,
    QKeyEvent,
    QMouseEvent,
    QPainter,
    QPainterPath,
    QPen,
    QResizeEvent,
    QWheelEvent,
)
from PySide6.QtWidgets import (
    QComboBox,
    QDoubleSpinBox,
    QGraphicsEllipseItem,
    QGraphicsItem,
    QGraphicsScene,
    QGraphicsView,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

from leafstudio.gui.layers import BOUNDARY_COLOR, vein_color
from leafstudio.gui.sketch_model import BOUNDARY, Sketch

HIT_PIXELS = 9.0
POINT_PIXELS = 9.0
EMPTY_VIEW = (-0.1, -0.5, 1.2, 1.0)  # x, y, width, height of the plane shown for a new sketch


def _pen(color: str, width: float) -> QPen:
    pen = QPen(QColor(color), width)
    pen.setCosmetic(True)  # width in pixels at any zoom
    return pen


class SketchView(QGraphicsView):
    """The drawing surface. Plane point (x, y) is scene point (x, -y), so y points up."""

    preview = Signal(object)  # Sketch while dragging
    committed = Signal(object, object, str)  # before, after, what was done
    selection_changed = Signal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setScene(QGraphicsScene(self))
        self.setRenderHint(QPainter.RenderHint.Antialiasing)
        self.setTransformationAnchor(QGraphicsView.ViewportAnchor.AnchorUnderMouse)
        self.setFocusPolicy(Qt.FocusPolicy.StrongFocus)
        self.setBackgroundBrush(QColor("#fbfbf7"))
        self.sketch = Sketch()
        self.active = BOUNDARY
        self.selected: tuple[int, int] | None = None
        self._drag: tuple[int, int] | None = None
        self._before: Sketch | None = None
        self._moved = False
        self._auto_fit = True  # refit on resize until the user zooms
        self.setSceneRect(-1e3, -1e3, 2e3, 2e3)

    # --- model ---------------------------------------------------------------------------------
    def set_sketch(self, sketch: Sketch, fit: bool = False) -> None:
        """Show `sketch`; `fit` zooms to it (a new document)."""
        self.sketch = sketch
        if self.active >= len(sketch.veins):
            self.active = BOUNDARY
        if self.selected is not None and not self._valid(self.selected):
            self.selected = None
        self._redraw()
        if fit:
            self.fit()
        self.selection_changed.emit()

    def _valid(self, ref: tuple[int, int]) -> bool:
        curve, index = ref
        if curve != BOUNDARY and curve >= len(self.sketch.veins):
            return False
        return 0 <= index < len(self.sketch.control(curve))

    def fit(self) -> None:
        """Zoom so that the whole sketch (or a default area when empty) fills the view."""
        points = np.vstack([self.sketch.boundary, *(v[:, :2] for v in self.sketch.veins)])
        if len(points) >= 2 and np.ptp(points, axis=0).max() > 0:
            lo, hi = points.min(axis=0), points.max(axis=0)
            pad = 0.08 * float((hi - lo).max())
            x, y, w, h = lo[0] - pad, -hi[1] - pad, hi[0] - lo[0] + 2 * pad, hi[1] - lo[1] + 2 * pad
        else:
            x, y, w, h = EMPTY_VIEW
        self.fitInView(x, y, w, h, Qt.AspectRatioMode.KeepAspectRatio)
        self._auto_fit = True

    def resizeEvent(self, event: QResizeEvent) -> None:
        super().resizeEvent(event)
        if self._auto_fit:
            self.fit()

    def plane_point(self, pos: QPointF) -> np.ndarray:
        """Plane coordinates of a viewport position."""
        scene = self.mapToScene(pos.toPoint())
        return np.array([scene.x(), -scene.y()])

    def view_point(self, xy: np.ndarray) -> QPointF:
        """Viewport position of a plane point."""
        return QPointF(self.mapFromScene(QPointF(float(xy[0]), float(-xy[1]))))

    # --- drawing -------------------------------------------------------------------------------
    def _redraw(self) -> None:
        scene = self.scene()
        scene.clear()
        outline = self.sketch.boundary_curve()
        if len(outline):
            scene.addPath(
                self._path(outline, closed=True),
                _pen(BOUNDARY_COLOR, 2),
                QBrush(QColor(120, 180, 90, 60)),
            )
        elif len(self.sketch.boundary) > 1:
            scene.addPath(self._path(self.sketch.boundary, closed=False), _pen("#909090", 1))
        for i in range(len(self.sketch.veins)):
            curve = self.sketch.vein_curve(i)
            if len(curve) > 1:
                scene.addPath(self._path(curve[:, :2], closed=False), _pen(vein_color(i), 2))
        for curve in (BOUNDARY, *range(len(self.sketch.veins))):
            color = BOUNDARY_COLOR if curve == BOUNDARY else vein_color(curve)
            for index, point in enumerate(self.sketch.control(curve)):
                self._dot(
                    point[:2],
                    color,
                    active=curve == self.active,
                    selected=self.selected == (curve, index),
                )

    @staticmethod
    def _path(points: np.ndarray, closed: bool) -> QPainterPath:
        path = QPainterPath(QPointF(points[0, 0], -points[0, 1]))
        for x, y in points[1:, :2]:
            path.lineTo(x, -y)
        if closed:
            path.closeSubpath()
        return path

    def _dot(self, xy: np.ndarray, color: str, active: bool, selected: bool) -> None:
        r = POINT_PIXELS / 2 * (1.0 if active else 0.75)
        item = QGraphicsEllipseItem(-r, -r, 2 * r, 2 * r)
        item.setFlag(QGraphicsItem.GraphicsItemFlag.ItemIgnoresTransformations)
        item.setPos(float(xy[0]), float(-xy[1]))
        item.setBrush(QBrush(QColor("#ffd400" if selected else ("white" if active else color))))
        item.setPen(_pen(color, 3 if selected else 2))
        self.scene().addItem(item)

    # --- editing -------------------------------------------------------------------------------
    def hit(self, pos: QPointF) -> tuple[int, int] | None:
        """The control point under a viewport position (active curve first), if any."""
        best, best_d = None, HIT_PIXELS
        curves = (
            self.active,
            *(c for c in (BOUNDARY, *range(len(self.sketch.veins))) if c != self.active),
        )
        for curve in curves:
            for index, point in enumerate(self.sketch.control(curve)):
                p = self.view_point(point)
                d = float(np.hypot(p.x() - pos.x(), p.y() - pos.y()))
                if d < best_d - 1e-9:
                    best, best_d = (curve, index), d
        return best

    def _commit(self, before: Sketch, after: Sketch, text: str) -> None:
        self.sketch = after
        self._redraw()
        self.selection_changed.emit()
        self.committed.emit(before, after, text)

    def add_point(self, xy: np.ndarray) -> None:
        """Add a control point at plane point `xy` to the active curve (a new vein if none)."""
        before = sketch = self.sketch
        if self.active == BOUNDARY:
            after, index = sketch.inserted(BOUNDARY, xy)
        else:
            after, index = sketch.inserted(self.active, xy, sketch.default_height(self.active, xy))
        self.selected = (self.active, index)
        self._commit(before, after, "Add point")

    def delete_selected(self) -> None:
        """Delete the selected control point."""
        if self.selected is None:
            return
        before = self.sketch
        after = before.deleted(*self.selected)
        self.selected = None
        self._commit(before, after, "Delete point")

    def set_height(self, height: float) -> None:
        """Set the height of the selected vein point."""
        if self.selected is None or self.selected[0] == BOUNDARY:
            return
        curve, index = self.selected
        if np.isclose(self.sketch.veins[curve][index, 2], height, rtol=0, atol=1e-12):
            return
        self._commit(self.sketch, self.sketch.with_height(curve, index, height), "Set height")

    def new_vein(self) -> None:
        """Start a new, empty vein and make it the active curve."""
        before = self.sketch
        after = before.with_new_vein()
        self.active = len(after.veins) - 1
        self.selected = None
        self._commit(before, after, "New vein")

    def mousePressEvent(self, event: QMouseEvent) -> None:
        pos = event.position()
        ref = self.hit(pos)
        if event.button() == Qt.MouseButton.RightButton:
            if ref is not None:
                self.selected = ref
                self.delete_selected()
            return
        if event.button() != Qt.MouseButton.LeftButton:
            super().mousePressEvent(event)
            return
        if ref is None:
            self.add_point(self.plane_point(pos))
            return
        self.selected, self.active = ref, ref[0]
        self._drag, self._before, self._moved = ref, self.sketch, False
        self._redraw()
        self.selection_changed.emit()

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        if self._drag is None:
            super().mouseMoveEvent(event)
            return
        self.sketch = self.sketch.moved(*self._drag, self.plane_point(event.position()))
        self._moved = True
        self._redraw()
        self.preview.emit(self.sketch)

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        if self._drag is not None and self._moved and self._before is not None:
            self.committed.emit(self._before, self.sketch, "Move point")
        self._drag, self._before, self._moved = None, None, False
        super().mouseReleaseEvent(event)

    def keyPressEvent(self, event: QKeyEvent) -> None:
        if event.key() in (Qt.Key.Key_Delete, Qt.Key.Key_Backspace):
            self.delete_selected()
            return
        super().keyPressEvent(event)

    def wheelEvent(self, event: QWheelEvent) -> None:
        self.scale(*(1.15 ** (event.angleDelta().y() / 120),) * 2)
        self._auto_fit = False


class SketchEditor(QWidget):
    """The sketch view with its tools: which curve to draw, a new vein, delete, height, fit."""

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
            "Height of the selected vein point above the leaf's plane (negative: below it)."
        )
        fit = QPushButton("Fit")
        fit.setToolTip("Zoom to the whole sketch.")
        curves, point = QHBoxLayout(), QHBoxLayout()  # two rows, so a narrow dock shows them
        for widget in (self.curve, self.new_vein, self.delete):
            curves.addWidget(widget)
        for widget in (QLabel("Height"), self.height, fit):
            point.addWidget(widget)
        for row in (curves, point):
            row.addStretch(1)
        hint = QLabel(
            "Click: add a point to the chosen curve · drag: move · right-click or Del: delete · "
            "wheel: zoom"
        )
        hint.setWordWrap(True)
        hint.setStyleSheet("color: #606060")
        layout = QVBoxLayout(self)
        layout.setContentsMargins(4, 4, 4, 4)
        layout.addLayout(curves)
        layout.addLayout(point)
        layout.addWidget(self.view, 1)
        layout.addWidget(hint)

        self.preview = self.view.preview
        self.committed = self.view.committed
        self.new_vein.clicked.connect(self.view.new_vein)
        self.delete.clicked.connect(self.view.delete_selected)
        fit.clicked.connect(self.view.fit)
        self.height.valueChanged.connect(self.view.set_height)
        self.curve.activated.connect(self._choose_curve)
        self.view.selection_changed.connect(self._sync_tools)
        self._sync_tools()

    def set_sketch(self, sketch: Sketch, fit: bool = False) -> None:
        """Show `sketch` (see SketchView.set_sketch)."""
        self.view.set_sketch(sketch, fit)

    def _choose_curve(self, row: int) -> None:
        self.view.active = BOUNDARY if row == 0 else row - 1
        self.view.selected = None
        self.view.set_sketch(self.view.sketch)

    def _sync_tools(self) -> None:
        view = self.view
        names = ["Boundary"] + [f"Vein {i + 1}" for i in range(len(view.sketch.veins))]
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
