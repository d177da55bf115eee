"""A small side view of the chosen vein: its height along its length, with handles to edit it.

x runs along the vein from its base (left) to its tip (right), y is the height above the leaf's
plane (the dashed line). The vein's own curve and points are drawn in its colour, the square
handles lie on it (gui/model/vein_profile.py). Like anchors in a vector editor:
- drag a handle: the vein bends there, between its neighbouring handles, live; a grab without a
  move changes nothing;
- double-click the line: a new handle there (no height changes); Delete/Backspace, a right-click
  or a double-click on a handle removes it (not the end ones), pulling the vein there onto the
  curve through the others;
- the keyboard: the view takes focus on a click or Tab; Left/Right or Tab/Shift+Tab choose a
  handle, Up/Down nudge it (1% of the sketch's size, with Shift 10%).
Each drag, each run of Up/Down presses (a key pressed, or held, until released) and each removal
that changes heights is one undo step: the editor turns `dragged` into previews and `released`
into one commit. Colours follow the palette; sizes are in logical pixels, so they follow the
device pixel ratio.
"""

from __future__ import annotations

from weakref import WeakKeyDictionary

import numpy as np
from PySide6.QtCore import QPointF, QRectF, QSize, Qt, Signal
from PySide6.QtGui import (
    QFocusEvent,
    QKeyEvent,
    QMouseEvent,
)
from PySide6.QtWidgets import QSizePolicy, QWidget

from leafstudio.gui.model.curves import plane_arc_lengths
from leafstudio.gui.model.sketch_model import BOUNDARY, Sketch
from leafstudio.gui.model.vein_profile import Profile, boundary_line
from leafstudio.gui.qt.profile_paint import MARGINS, ProfilePainting

HIT_PIXELS = 10.0
PAD = 0.2  # share of the height range left above and below the drawn heights
NUDGE = 0.01  # an Up/Down press moves a handle by this share of the sketch's size
BIG_NUDGE = 0.1  # with Shift
NUDGE_KEYS = (Qt.Key.Key_Up, Qt.Key.Key_Down)


class ProfileView(ProfilePainting, QWidget):
    """The side view; `set_vein(sketch, vein)` shows a vein (BOUNDARY: the boundary's heights,
    read only; an index past the veins: none).

    Signals
    -------
    dragged(Sketch)
        The sketch with the vein's heights as the edit under way (a drag, held keys) makes them.
    released(Sketch, Sketch)
        The sketch before an edit and after it: a drag let go, a run of key presses ended, a
        handle removed.
    """

    dragged = Signal(object)
    released = Signal(object, object)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.sketch = Sketch()
        self.vein = -1
        self.profile: Profile | None = None
        self.selected: int | None = None  # the handle the keyboard works on
        self.grabbed: int | None = None  # the handle being dragged
        self._count = 0  # the shown vein's control points (its handles are kept while the same)
        self._before: Sketch | None = None  # the sketch when the edit under way began
        self._base: tuple[np.ndarray, np.ndarray] | None = None  # its vein's shares and heights
        self._handles_before: np.ndarray | None = None  # the handles' places when it began
        self._dropped = False  # an edit was dropped: a held key's repeats do not resume it
        # the handles' places (per vein) of the sketches before and after each edit, so that an
        # undo or redo of a removal or a drag brings them back with the heights
        self._remembered: WeakKeyDictionary[Sketch, dict[int, np.ndarray]] = WeakKeyDictionary()
        self._offset = QPointF()  # from the cursor to the grabbed handle's centre
        self._range: tuple[float, float] | None = None  # heights shown; held during a drag
        self._range_of: tuple | None = None  # the last range worked out, and for what
        self._outline = (np.zeros(0), np.zeros(0), np.zeros(0))  # the boundary's (boundary_line)
        self.setMinimumHeight(96)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        self.setFocusPolicy(Qt.FocusPolicy.StrongFocus)  # a click or Tab: keys work on handles
        self.setMouseTracking(True)  # the cursor shows where a handle can be grabbed
        self.setToolTip(
            "The chosen vein's height along it, from its base (left) to its tip (right); the "
            "dashed line is the leaf's plane. Drag a square handle to bend the vein there, "
            "between its neighbouring handles. Double-click the line to add a handle; "
            "Delete, right-click or double-click a handle to remove it. Keys: Left/Right or Tab "
            "choose a handle, Up/Down move it (Shift: more). One undo step per drag, run of "
            "key presses or removal."
        )

    def sizeHint(self) -> QSize:
        return QSize(320, 120)

    # --- model ---------------------------------------------------------------------------------
    def set_vein(self, sketch: Sketch, vein: int) -> None:
        """Show vein `vein` of `sketch`. The handles stay where they are along the same vein
        with as many points (after an edit, an undo, a height typed in), lying on its new
        heights; another vein gets handles anew. An edit under way (a drag, held keys) ends
        without a step when another sketch arrives (an undo, a redo, a new document): its
        before-sketch is no longer the document's, so its step would bring that back."""
        if vein != self.vein:
            self.grabbed, self._before, self._base, self.selected = None, None, None, None
        elif self._before is not None and sketch is not self.sketch:
            self.drop_edit()
        keep = vein == self.vein and self.profile is not None
        self.sketch, self.vein = sketch, vein
        empty = np.zeros(0)
        self._outline = boundary_line(sketch) if vein == BOUNDARY else (empty, empty, empty)
        if not self.has_vein():
            self.profile, self.selected = None, None
        elif self._before is None:  # no edit under way (its previews come back here)
            # a sketch this view edited, shown again (an undo, a redo): its handles
            at = self._remembered.get(sketch, {}).get(vein)
            if at is None and keep and len(sketch.veins[vein]) == self._count:
                at = self.profile.t
            self._rebuild(at)
            self._range = None
        self.update()

    def has_vein(self) -> bool:
        return 0 <= self.vein < len(self.sketch.veins)

    def has_boundary(self) -> bool:
        """The boundary is shown (chosen, with 3 control points or more)."""
        return self.vein == BOUNDARY and len(self._outline[0]) > 0

    def _vein_shares(self) -> tuple[np.ndarray, np.ndarray]:
        return self.sketch.vein_fractions(self.vein), self.sketch.veins[self.vein][:, 2].copy()

    def _line(self) -> tuple[np.ndarray, np.ndarray]:
        """The vein's heights along its curve: (shares of its length, heights)."""
        curve = self.sketch.vein_curve(self.vein)
        arc = plane_arc_lengths(curve)
        shares = arc / arc[-1] if arc[-1] > 0 else np.linspace(0.0, 1.0, len(arc))
        return shares, curve[:, 2]

    def _rebuild(self, at: np.ndarray | None) -> None:
        """Handles on the vein's current heights, at shares `at` (None: spread anew)."""
        self.profile = Profile.of_vein(*self._vein_shares(), self._line(), at)
        self._count = len(self.sketch.veins[self.vein])
        if self.selected is not None and self.selected >= len(self.profile.t):
            self.selected = len(self.profile.t) - 1

    # --- editing -------------------------------------------------------------------------------
    def drop_edit(self) -> None:
        """End the edit under way, if any, with no step: the document changed under it (an
        undo, a redo, a new document), so its step would start from a sketch that is no longer
        the document's. A held Up/Down does nothing more until pressed again."""
        if self._before is not None or self.grabbed is not None:
            self._dropped = True
        self.grabbed, self._before, self._base, self._range = None, None, None, None

    def _begin(self) -> None:
        """Start an edit (a drag, a run of key presses) from the vein's present heights."""
        self._before, self._base = self.sketch, self._vein_shares()
        self._handles_before = self.profile.t.copy()

    def _remember(self, before: Sketch, handles_before: np.ndarray, after: Sketch) -> None:
        """Keep where the handles were on `before` and are on `after` (see set_vein)."""
        self._remembered.setdefault(before, {})[self.vein] = handles_before
        self._remembered.setdefault(after, {})[self.vein] = self.profile.t.copy()

    def _show(self, profile: Profile) -> None:
        """During an edit: the vein's heights as `profile` makes them, shown and sent on."""
        self.profile = profile
        self.sketch = self.sketch.with_heights(self.vein, profile.applied(*self._base))
        self.update()
        self.dragged.emit(self.sketch)

    def _finish(self) -> None:
        """End the edit under way: one undo step if it changed a height."""
        before, after, handles = self._before, self.sketch, self._handles_before
        self.grabbed, self._before, self._base, self._range = None, None, None, None
        if before is None or not self.has_vein():
            return
        self._rebuild(self.profile.t)
        self.update()
        if after is not before:
            self._remember(before, handles, after)
            self.released.emit(before, after)

    def add_handle(self, t: float) -> int | None:
        """Add a handle at share `t` of the vein's length, on the profile (no height changes),
        and select it; None when too close to another handle."""
        if self.profile is None or self._before is not None:
            return None
        added = self.profile.with_handle(t)
        if added is None:
            return None
        self.profile, self.selected = added
        self.update()
        return self.selected

    def remove_handle(self, index: int) -> bool:
        """Remove inner handle `index`: the vein there is pulled onto the curve through the
        other handles (between its neighbours); one undo step when a height changed."""
        if self.profile is None or not 0 < index < len(self.profile.t) - 1:
            return False
        self._finish()
        before = self.sketch
        fractions, heights = self._vein_shares()
        after_heights = self.profile.bridged(index).applied(fractions, heights)
        tolerance = 1e-12 * self.sketch.extent()
        if np.any(np.abs(after_heights - heights) > tolerance):
            self.sketch = before.with_heights(self.vein, after_heights)
        handles = self.profile.t.copy()
        self._rebuild(np.delete(handles, index))
        self.selected = None if self.selected is None else min(index, len(handles) - 2)
        self.update()
        if self.sketch is not before:
            self._remember(before, handles, self.sketch)
            self.released.emit(before, self.sketch)
        return True

    def select(self, index: int | None) -> None:
        """Select handle `index` (None: none)."""
        if self.profile is not None and index is not None:
            index = int(np.clip(index, 0, len(self.profile.t) - 1))
        self.selected = index if self.profile is not None else None
        self.update()

    def nudge(self, steps: float) -> None:
        """Move the selected handle up by `steps` nudges (a share NUDGE of the sketch's size
        each), as part of a run of key presses that `_finish` ends."""
        if self.profile is None or self.selected is None or self.grabbed is not None:
            return
        if self._before is None:
            self._begin()
        i = self.selected
        step = steps * NUDGE * self.sketch.extent()
        self._show(self.profile.moved(i, self.profile.t[i], self.profile.h[i] + step))

    # --- geometry ------------------------------------------------------------------------------
    def _plot(self) -> QRectF:
        left, top, right, bottom = MARGINS
        return QRectF(
            left, top, max(self.width() - left - right, 1), max(self.height() - top - bottom, 1)
        )

    def _heights_range(self) -> tuple[float, float]:
        """The heights the plot spans (held during a drag; worked out once per shown sketch,
        profile and curve, as every drawn point asks for it)."""
        if self._range is not None:
            return self._range
        cached = self._range_of
        if (
            cached
            and cached[0] is self.sketch
            and cached[1] is self.profile
            and cached[2] == self.vein
        ):
            return cached[3]
        values = [0.0]
        if self.has_vein():
            values += list(self.sketch.vein_curve(self.vein)[:, 2])
        values += list(self._outline[1])
        if self.profile is not None:
            values += list(self.profile.h)
        lo, hi = min(values), max(values)
        pad = max(PAD * (hi - lo), 0.02 * self.sketch.extent())
        self._range_of = (self.sketch, self.profile, self.vein, (lo - pad, hi + pad))
        return lo - pad, hi + pad

    def to_view(self, t: float, h: float) -> QPointF:
        """Widget position of share `t` of the vein's length at height `h`."""
        return QPointF(*self.view_xy(t, h))

    def view_xy(self, t, h) -> tuple:
        """Widget x and y of shares `t` of the vein's length at heights `h` (numbers, or arrays
        for a whole line: ProfilePainting._path)."""
        plot, (lo, hi) = self._plot(), self._heights_range()
        return plot.left() + t * plot.width(), plot.bottom() - (h - lo) / (hi - lo) * plot.height()

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

    def on_line(self, pos: QPointF) -> float | None:
        """The share of the length where the profile line passes within HIT_PIXELS of a widget
        position (the nearest of its samples), if it does."""
        if self.profile is None:
            return None
        plot, (lo, hi) = self._plot(), self._heights_range()
        t = np.linspace(0.0, 1.0, max(int(plot.width()), 2) + 1)  # a sample per pixel
        x = plot.left() + t * plot.width()
        y = plot.bottom() - (self.profile.heights(t) - lo) / (hi - lo) * plot.height()
        d = np.hypot(x - pos.x(), y - pos.y())
        best = int(np.argmin(d))
        return float(t[best]) if d[best] <= HIT_PIXELS else None

    # --- the mouse -----------------------------------------------------------------------------
    def mousePressEvent(self, event: QMouseEvent) -> None:
        if self._before is not None and self.grabbed is None:
            self._finish()  # keys were held: their run ends here
        pos = event.position()
        index = self.handle_at(pos)
        if event.button() == Qt.MouseButton.RightButton:
            if index is not None:
                self.remove_handle(index)
            return
        if event.button() != Qt.MouseButton.LeftButton:
            super().mousePressEvent(event)
            return
        self.selected = self.grabbed = index
        if index is not None:
            self._range = self._heights_range()  # the scale holds still under the hand
            self._offset = self.to_view(self.profile.t[index], self.profile.h[index]) - pos
            self._begin()
        self.update()

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        if self.grabbed is None or self.profile is None:
            shape = Qt.CursorShape.ArrowCursor  # the cursor tells what a click would do there
            if self.handle_at(event.position()) is not None:
                shape = Qt.CursorShape.SizeAllCursor  # drag
            elif self.on_line(event.position()) is not None:
                shape = Qt.CursorShape.CrossCursor  # double-click: a new handle
            self.setCursor(shape)
            super().mouseMoveEvent(event)
            return
        t, h = self.from_view(event.position() + self._offset)
        self._show(self.profile.moved(self.grabbed, t, h))

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        if self.grabbed is not None:
            self._finish()
        super().mouseReleaseEvent(event)

    def mouseDoubleClickEvent(self, event: QMouseEvent) -> None:
        if event.button() != Qt.MouseButton.LeftButton:
            super().mouseDoubleClickEvent(event)
            return
        pos = event.position()
        index = self.handle_at(pos)
        if index is not None:
            self.remove_handle(index)
            return
        t = self.on_line(pos)
        if t is not None:
            self.add_handle(t)

    # --- the keyboard --------------------------------------------------------------------------
    def keyPressEvent(self, event: QKeyEvent) -> None:
        key, count = event.key(), 0 if self.profile is None else len(self.profile.t)
        if key in NUDGE_KEYS and event.isAutoRepeat() and self._dropped:
            return  # the run this key began was dropped: its repeats do not start another
        self._dropped = False
        if key in NUDGE_KEYS and self.selected is not None and self.grabbed is None:
            shift = event.modifiers() & Qt.KeyboardModifier.ShiftModifier
            steps = BIG_NUDGE / NUDGE if shift else 1.0
            self.nudge(steps if key == Qt.Key.Key_Up else -steps)
        elif key in (Qt.Key.Key_Left, Qt.Key.Key_Right) and count and self.grabbed is None:
            right = key == Qt.Key.Key_Right
            if self.selected is None:
                self.select(0 if right else count - 1)
            else:
                self.select(self.selected + (1 if right else -1))
        elif key in (Qt.Key.Key_Delete, Qt.Key.Key_Backspace) and self.selected is not None:
            self.remove_handle(self.selected)
        elif key == Qt.Key.Key_Escape and self.selected is not None:
            self.select(None)
        else:
            super().keyPressEvent(event)

    def keyReleaseEvent(self, event: QKeyEvent) -> None:
        if event.key() in NUDGE_KEYS and not event.isAutoRepeat() and self.grabbed is None:
            self._finish()  # a key pressed (or held) and let go: one undo step
        super().keyReleaseEvent(event)

    def focusNextPrevChild(self, next: bool) -> bool:
        """Tab and Shift+Tab go through the handles (from the first or the last when none is
        chosen), then on to the next widget."""
        if self.hasFocus() and self.profile is not None:
            if self.selected is None:
                index = 0 if next else len(self.profile.t) - 1
            else:
                index = self.selected + (1 if next else -1)
            if 0 <= index < len(self.profile.t):
                self.select(index)
                return True
        return super().focusNextPrevChild(next)

    def focusInEvent(self, event: QFocusEvent) -> None:
        if self.selected is None and self.profile is not None:
            if event.reason() == Qt.FocusReason.TabFocusReason:
                self.select(0)
            elif event.reason() == Qt.FocusReason.BacktabFocusReason:
                self.select(len(self.profile.t) - 1)
        self.update()
        super().focusInEvent(event)

    def focusOutEvent(self, event: QFocusEvent) -> None:
        if self._before is not None and self.grabbed is None:
            self._finish()  # keys held as the focus left
        self.update()
        super().focusOutEvent(event)
