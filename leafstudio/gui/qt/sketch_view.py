"""The sketch's drawing on the leaf plane (SketchView): control points of the boundary (a closed
spline) and of each vein (open splines) to click, drag and delete, the curves through them, and
where the boundary crosses itself, in red. The view moves only when asked (Fit, the wheel) or
when a document opens. SketchEditor (sketch.py) puts it among its tools.
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
    QPalette,
    QPen,
    QResizeEvent,
    QWheelEvent,
)
from PySide6.QtWidgets import (
    QGraphicsEllipseItem,
    QGraphicsItem,
    QGraphicsPathItem,
    QGraphicsScene,
    QGraphicsView,
    QWidget,
)

from leafstudio.gui.model.layers import BOUNDARY_COLOR, vein_color
from leafstudio.gui.model.sketch_model import BOUNDARY, Sketch
from leafstudio.gui.qt.leaf_picture import polyline_path

HIT_PIXELS = 9.0
SNAP_PIXELS = 14.0  # a new vein's first click this close to a vein branches from it
POINT_PIXELS = 9.0
FIT_MARGIN = 0.1  # Fit leaves this share of the sketch's size around it
EMPTY_VIEW = (-0.1, -0.5, 1.2, 1.0)  # x, y, width, height of the plane shown for a new sketch
CROSSING_COLOR = "#e00000"
SELECT_MODIFIERS = Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier


def _pen(color: str, width: float) -> QPen:
    pen = QPen(QColor(color), width)
    pen.setCosmetic(True)  # width in device pixels at any zoom (SketchView.pen scales it)
    return pen


class SketchView(QGraphicsView):
    """The drawing surface. Plane point (x, y) is scene point (x, -y), so y points up."""

    preview = Signal(object)  # Sketch while dragging
    committed = Signal(object, object, str)  # before, after, what was done
    mirror_changed = Signal(bool)  # Mirror turned on or off (a property of the sketch)
    mirror_problem = Signal(str)  # why the last edit was not mirrored ("" when it was)
    selection_changed = Signal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setScene(QGraphicsScene(self))
        self.setRenderHint(QPainter.RenderHint.Antialiasing)
        self.setTransformationAnchor(QGraphicsView.ViewportAnchor.AnchorUnderMouse)
        self.setFocusPolicy(Qt.FocusPolicy.StrongFocus)
        self.sketch = Sketch()
        self.active = BOUNDARY  # a vein index; len(sketch.veins): a new vein, made by a click
        self.select_tool = False  # True: a click selects any point instead of adding one
        self.crossings = np.zeros((0, 2))
        self.selected: tuple[int, int] | None = None
        self._drag: tuple[int, int] | None = None
        self._before: Sketch | None = None
        self._moved = False
        self._auto_fit = True  # keep the fitted area in view on resize until the user zooms
        self._fitted = EMPTY_VIEW
        self._drawn: tuple | None = None  # what the scene shows (_drawing), None: redraw
        self.setSceneRect(-1e3, -1e3, 2e3, 2e3)
        self.apply_palette()

    def apply_palette(self) -> None:
        """The canvas follows the palette (light or dark)."""
        self.setBackgroundBrush(self.palette().color(QPalette.ColorRole.Base))

    def changeEvent(self, event) -> None:
        super().changeEvent(event)
        if event.type() == event.Type.PaletteChange:
            self.apply_palette()
            self._redraw()

    def event(self, event) -> bool:
        if event.type() == event.Type.DevicePixelRatioChange:  # another screen: pen widths
            self._redraw()
        return super().event(event)

    def pen(self, color: str, width: float) -> QPen:
        """A cosmetic pen `width` logical pixels wide: a cosmetic pen's width is in device
        pixels, which are half as wide at a pixel ratio of 2."""
        return _pen(color, width * self.devicePixelRatioF())

    # --- model ---------------------------------------------------------------------------------
    def set_sketch(self, sketch: Sketch, fit: bool = False) -> None:
        """Show `sketch`; `fit` zooms to it (a new document: drawing starts on its boundary,
        nothing selected, never on the last document's chosen vein or point). A point drag
        under way ends without a step when another sketch arrives (an undo, a redo, a new
        document): its point may be gone, and its step would start from the old sketch."""
        if sketch is not self.sketch:
            self.drop_drag()
        self.sketch = sketch
        if fit:
            self.active, self.selected = BOUNDARY, None
        if self.active > len(sketch.veins):
            self.active = BOUNDARY
        if self.selected is not None and not self._valid(self.selected):
            self.selected = None
        if self._drawing() != self._drawn:  # a pose changed in the Forms dock: the same blade
            self._redraw()
        if fit:
            self.fit()
        self.selection_changed.emit()

    def drop_drag(self) -> None:
        """End a point drag under way, if any, with no step (see SketchEditor.drop_edit)."""
        self._drag, self._before, self._moved = None, None, False

    def _valid(self, ref: tuple[int, int]) -> bool:
        curve, index = ref
        if curve != BOUNDARY and curve >= len(self.sketch.veins):
            return False
        return 0 <= index < len(self.sketch.control(curve))

    def fit(self) -> None:
        """Zoom so that the whole leaf (its curves, not only the points) fills the view with a
        margin; a default area when the sketch is empty. Read from the drawn scene (its paths
        and points), not from the sketch's curves made again (a third of a new document's
        main-thread time: 13 veins' splines)."""
        corners = []
        for item in self.scene().items():
            if isinstance(item, QGraphicsPathItem):
                bounds = item.path().boundingRect()
                corners += [bounds.topLeft(), bounds.bottomRight()]
            else:  # a point (drawn the same size at any zoom: its position only)
                corners.append(item.pos())
        points = np.array([(p.x(), p.y()) for p in corners]).reshape(-1, 2)  # scene: y down
        if len(points) >= 2 and np.ptp(points, axis=0).max() > 0:
            lo, hi = points.min(axis=0), points.max(axis=0)
            pad = FIT_MARGIN * float((hi - lo).max())
            x, y, w, h = lo[0] - pad, lo[1] - pad, hi[0] - lo[0] + 2 * pad, hi[1] - lo[1] + 2 * pad
        else:
            x, y, w, h = EMPTY_VIEW
        self._fitted = (x, y, w, h)
        self.fitInView(x, y, w, h, Qt.AspectRatioMode.KeepAspectRatio)
        self._auto_fit = True

    def resizeEvent(self, event: QResizeEvent) -> None:
        super().resizeEvent(event)
        if self._auto_fit:  # the area fitted last stays in view; points added since do not move it
            self.fitInView(*self._fitted, Qt.AspectRatioMode.KeepAspectRatio)

    def set_crossings(self, points: np.ndarray) -> None:
        """Mark where the boundary crosses itself ((c, 2) plane points; none: empty)."""
        points = np.asarray(points, dtype=float).reshape(-1, 2)
        if len(points) == 0 and len(self.crossings) == 0:
            return
        self.crossings = points
        self._redraw()

    def plane_point(self, pos: QPointF) -> np.ndarray:
        """Plane coordinates of a viewport position."""
        scene = self.mapToScene(pos.toPoint())
        return np.array([scene.x(), -scene.y()])

    def view_point(self, xy: np.ndarray) -> QPointF:
        """Viewport position of a plane point."""
        return QPointF(self.mapFromScene(QPointF(float(xy[0]), float(-xy[1]))))

    # --- drawing -------------------------------------------------------------------------------
    def _drawing(self) -> tuple:
        """What _redraw draws, as bytes and values: the sketch's curves in the plane (the
        boundary's relief gives only heights), its holes, the marks and the pens' colours."""
        sketch = self.sketch
        return (
            np.ascontiguousarray(sketch.boundary[:, :2]).tobytes(),
            tuple(np.ascontiguousarray(vein).tobytes() for vein in sketch.veins),
            tuple(ring.tobytes() for ring in sketch.hole_curves()),
            np.asarray(self.crossings).tobytes(),
            self.active,
            self.selected,
            self.palette().color(QPalette.ColorRole.Text).name(),
            self.palette().color(QPalette.ColorRole.Base).name(),
            self.devicePixelRatioF(),
        )

    def _redraw(self) -> None:
        self._drawn = self._drawing()
        scene = self.scene()
        scene.clear()
        outline = self.sketch.boundary_curve()
        crossing = len(self.crossings) > 0
        ink = self.palette().color(QPalette.ColorRole.Text).name()
        boundary_color = (
            BOUNDARY_COLOR
            if self.palette().color(QPalette.ColorRole.Base).lightnessF() >= 0.5
            else ink
        )
        if len(outline):
            scene.addPath(
                self._path(outline, closed=True),
                self.pen(CROSSING_COLOR if crossing else boundary_color, 2),
                QBrush(QColor(220, 60, 60, 40) if crossing else QColor(120, 180, 90, 60)),
            )
        elif len(self.sketch.boundary) > 1:
            scene.addPath(self._path(self.sketch.boundary, closed=False), self.pen("#909090", 1))
        base = self.palette().color(QPalette.ColorRole.Base)
        for ring in self.sketch.hole_curves():  # a scan's real holes: open in the mesh too
            scene.addPath(self._path(ring, closed=True), self.pen(boundary_color, 1), QBrush(base))
        for i in range(len(self.sketch.veins)):
            curve = self.sketch.vein_curve(i)
            if len(curve) > 1:
                scene.addPath(self._path(curve[:, :2], closed=False), self.pen(vein_color(i), 2))
        for xy in self.crossings:
            r = 1.6 * POINT_PIXELS
            ring = QGraphicsEllipseItem(-r, -r, 2 * r, 2 * r)
            ring.setFlag(QGraphicsItem.GraphicsItemFlag.ItemIgnoresTransformations)
            ring.setPos(float(xy[0]), float(-xy[1]))
            ring.setPen(self.pen(CROSSING_COLOR, 3))
            scene.addItem(ring)
        for curve in (BOUNDARY, *range(len(self.sketch.veins))):
            color = boundary_color if curve == BOUNDARY else vein_color(curve)
            for index, point in enumerate(self.sketch.control(curve)):
                self._dot(
                    point[:2],
                    color,
                    active=curve == self.active,
                    selected=self.selected == (curve, index),
                )

    @staticmethod
    def _path(points: np.ndarray, closed: bool) -> QPainterPath:
        """A polyline through (n, 2+) plane points, in the scene (y up)."""
        xy = np.asarray(points, dtype=float)
        return polyline_path(np.column_stack([xy[:, 0], -xy[:, 1]]), closed)

    def _dot(self, xy: np.ndarray, color: str, active: bool, selected: bool) -> None:
        r = POINT_PIXELS / 2 * (1.0 if active else 0.75)
        item = QGraphicsEllipseItem(-r, -r, 2 * r, 2 * r)
        item.setFlag(QGraphicsItem.GraphicsItemFlag.ItemIgnoresTransformations)
        item.setPos(float(xy[0]), float(-xy[1]))
        item.setBrush(QBrush(QColor("#ffd400" if selected else ("white" if active else color))))
        item.setPen(self.pen(color, 3 if selected else 2))
        self.scene().addItem(item)

    # --- editing -------------------------------------------------------------------------------
    def hit(self, pos: QPointF, only_active: bool = False) -> tuple[int, int] | None:
        """The control point under a viewport position (active curve first), if any;
        `only_active`: of the active curve only."""
        best, best_d = None, HIT_PIXELS
        every = (BOUNDARY, *range(len(self.sketch.veins)))
        curves = [c for c in (self.active,) if c in every]
        if not only_active:
            curves += [c for c in every if c != self.active]
        for curve in curves:
            for index, point in enumerate(self.sketch.control(curve)):
                p = self.view_point(point)
                d = float(np.hypot(p.x() - pos.x(), p.y() - pos.y()))
                if d < best_d - 1e-9:
                    best, best_d = (curve, index), d
        return best

    @property
    def mirror(self) -> bool:
        """Mirror editing is on: the sketch's own flag (saved with it, see Sketch.symmetric)."""
        return self.sketch.symmetric

    def _mirrored(self, sketch: Sketch, xy: np.ndarray | None) -> Sketch:
        """With Mirror on, `sketch` made symmetric from the side of plane point `xy` (an edit
        there); as it is otherwise, or without `xy`."""
        if not self.mirror or xy is None:
            return sketch
        mirrored, fold = sketch.mirror_edit(xy)
        self.mirror_problem.emit(fold.message() if fold is not None else "")
        return mirrored

    def _commit(self, before: Sketch, after: Sketch, text: str, xy=None) -> None:
        after = self._mirrored(after, xy)
        self.sketch = after
        self._redraw()
        self.selection_changed.emit()
        self.committed.emit(before, after, text)

    def _plane_tolerance(self, pixels: float) -> float:
        """`pixels` of the view as a plane distance at the current zoom."""
        return pixels / max(abs(self.transform().m11()), 1e-12)

    def add_point(self, xy: np.ndarray) -> None:
        """Add a control point at plane point `xy` to the active curve. A new vein's first point
        snaps onto a vein nearby (the new vein branches from it) and takes its height there."""
        before = sketch = self.sketch
        xy = np.asarray(xy, dtype=float)
        if self.active == BOUNDARY:
            after, index = sketch.inserted(BOUNDARY, xy)
        elif self.active >= len(sketch.veins):
            after, index = sketch.started_vein(xy, self._plane_tolerance(SNAP_PIXELS)), 0
            self.active = len(after.veins) - 1
            self.selected = (self.active, index)
            self._commit(before, after, "New vein", xy)
            return
        else:
            after, index = sketch.inserted(self.active, xy, sketch.default_height(self.active, xy))
        self.selected = (self.active, index)
        self._commit(before, after, "Add point", xy)

    def delete_selected(self) -> None:
        """Delete the selected control point."""
        if self.selected is None:
            return
        before = self.sketch
        curve = self.selected[0]
        after = before.deleted(*self.selected)
        if len(after.veins) < len(before.veins) and self.active >= curve != BOUNDARY:
            self.active = BOUNDARY if self.active == curve else self.active - 1
        xy = before.control(curve)[self.selected[1], :2]
        self.selected = None
        self._commit(before, after, "Delete point", xy)

    def set_height(self, height: float) -> None:
        """Set the height of the selected vein point."""
        if self.selected is None or self.selected[0] == BOUNDARY:
            return
        curve, index = self.selected
        if np.isclose(self.sketch.veins[curve][index, 2], height, rtol=0, atol=1e-12):
            return
        self._commit(self.sketch, self.sketch.with_height(curve, index, height), "Set height")

    def new_vein(self) -> None:
        """Make the next click start a new vein (no vein exists until then)."""
        self.active = len(self.sketch.veins)
        self.selected = None
        self.select_tool = False
        self._redraw()
        self.selection_changed.emit()

    def set_profile(self, start: float, end: float) -> None:
        """Set the heights of the active vein from `start` at its first point to `end` at its
        last (linear along the vein): one undo step."""
        if not 0 <= self.active < len(self.sketch.veins):
            return
        self.commit_heights(self.sketch, self.sketch.with_profile(self.active, start, end))

    def _side_vein_at(self, sketch: Sketch) -> np.ndarray | None:
        """Where the active vein lies when it is a side vein (its points' mean), for mirroring
        its heights onto its counterpart; None for the midrib or no vein."""
        if not 0 < self.active < len(sketch.veins):
            return None
        return sketch.veins[self.active][:, :2].mean(axis=0)

    def preview_heights(self, sketch: Sketch) -> None:
        """The active vein's heights during a profile drag: shown and sent on as a preview
        (with Mirror on, a side vein's counterpart follows)."""
        self.sketch = self._mirrored(sketch, self._side_vein_at(sketch))
        self._redraw()
        self.preview.emit(self.sketch)

    def commit_heights(self, before: Sketch, after: Sketch) -> None:
        """The active vein's new heights (a profile set or dragged): one undo step."""
        self._commit(before, after, "Vein profile", self._side_vein_at(after))

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
        selecting = self.select_tool or bool(event.modifiers() & SELECT_MODIFIERS)
        if not selecting:  # drawing: a click adds, and only the active curve's points are grabbed
            ref = self.hit(pos, only_active=True)
            if ref is None:
                self.add_point(self.plane_point(pos))
                return
        elif ref is None:
            self.selected = None
            self._redraw()
            self.selection_changed.emit()
            return
        self.selected, self.active = ref, ref[0]
        self._drag, self._before, self._moved = ref, self.sketch, False
        self._redraw()
        self.selection_changed.emit()

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        if self._drag is None:
            super().mouseMoveEvent(event)
            return
        xy = self.plane_point(event.position())
        self.sketch = self._mirrored(self.sketch.moved(*self._drag, xy), xy)
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
