"""The lesson mode (View > Lesson, `leafstudio gui --lesson FILE`): a window of its own, shown
full screen over the app, one step of the method per screen (render/lesson.LESSON_STEPS, walked
by gui/model/lesson.py). The 3D leaf on the left, with the step's layers, in a 3D view of its
own; beside it the step's title, its plan view (the slides' picture of the step), its caption in
plain words and its equation typeset. Nothing is drawn over the leaf. The arrow keys and the
space bar move between the steps, Escape leaves.

The 3D view and every plan show the leaf the same way round, and as the app's main view does:
on the result's plane turned as the main view's frame (step_slides.plan_frame of
Session.view_frame), the 3D view from that frame's -v side. A loaded leaf, a scan or a demo is
shown base left, apex right (its sketch is derived on its view frame); a drawn leaf at the angle
it was drawn. In step 5 soybean pot1_1's apex was at the plan's upper left and the 3D view's
right, and the nested demo's ran at 44° across the 3D view (its iso camera turned towards the
base); a leaf drawn at 40° ran level in the lesson and at 40° in the app (closing34).

Why the drawing's angle, for a teacher: the class has watched the leaf drawn, and goes back to
the app with Esc; the same leaf turned 40° on the next screen reads as another leaf, or as a
step of the method, which does not turn it (its plane's axes are a change of coordinates). The
app's view cannot be straightened instead: its top view is the sketch the teacher draws in.
"""

from __future__ import annotations

import contextlib
from collections.abc import Sequence

from PySide6.QtCore import QPoint, QRect, Qt, QTimer
from PySide6.QtGui import (
    QCloseEvent,
    QFont,
    QGuiApplication,
    QKeyEvent,
    QPainter,
    QPixmap,
    QResizeEvent,
)
from PySide6.QtWidgets import QHBoxLayout, QLabel, QSizePolicy, QVBoxLayout, QWidget

from leafstudio.core.plane import Frame
from leafstudio.gui.model.lesson import (
    Lesson,
    bent_notes,
    equation_png,
    lesson_bounds,
    plan_png,
    step_layers,
)
from leafstudio.gui.model.view_aids import stretches
from leafstudio.gui.qt.actions import Action
from leafstudio.gui.qt.explain import stretch_matrix
from leafstudio.gui.qt.viewport import Viewport
from leafstudio.render.step_slides import POINTS_ELEVATION, plan_frame

TITLE_PT, CAPTION_PT, FOOTER_PT = 26, 18, 14  # at 100% scaling; none under 14 (issue 22)
STRETCH = 3.0  # the 3D leaf's relief, exaggerated: a few percent of its length is flat to a class
MINIMUM = (960, 600)  # below this, the words of a step no longer fit beside the leaf
TEXT_SHARE = 0.44  # the text column's share of the width: the 3D view keeps the rest
NEXT_KEYS = frozenset({Qt.Key.Key_Right, Qt.Key.Key_Space, Qt.Key.Key_PageDown, Qt.Key.Key_Down})
BACK_KEYS = frozenset({Qt.Key.Key_Left, Qt.Key.Key_Backspace, Qt.Key.Key_PageUp, Qt.Key.Key_Up})
# the 3D view's elevations (framing.best_iso), nearer the plan's view from straight above than
# the app's 35° to 65°: from across the blade at 35°, an ovate form folded 45° showed its near
# half's underside and hid its crease (the nested demo takes 50° either way)
ELEVATIONS = (POINTS_ELEVATION, 65.0)
# the footer's keys (space: next too), the first that fits the column on one line: at 960 x 600
# the first took 385 of the column's 374 pixels (14-point Sans under Xvfb) and "Esc: leave"
# wrapped; the second took 358, the third is for a larger font. A bent leaf's note goes under
# them, one line too (lesson.bent_notes)
FOOTERS = (
    "{progress} · → next · ← back · Esc: leave",
    "{progress} · ← → to move · Esc: leave",
    "{progress} · Esc: leave",
)
PLAN_LEAST = 0.3  # the plan's least share of the column's height: the caption's words are set
# smaller, down to 14 points, to leave it that (a folded leaf's step 2 at 960 x 600 left the
# plan 67 pixels high under a 13-line caption and a 3-line footer)
CAPTION_STEPS = (CAPTION_PT, 16.0, FOOTER_PT)  # the caption's sizes tried, largest first


def _label_height(label: QLabel, width: int) -> int:
    """The height `label` takes at `width` pixels: its words wrapped, or its picture's."""
    if label.wordWrap():
        return label.heightForWidth(width)
    return label.sizeHint().height()


def _font(points: float, bold: bool = False) -> QFont:
    font = QFont()
    font.setPointSizeF(points)
    font.setBold(bold)
    return font


class LessonWindow(QWidget):
    """The lesson over `window`'s session: shows its current result, and each new one."""

    def __init__(self, window) -> None:
        super().__init__(None, Qt.WindowType.Window)
        self.window_ = window
        self.lesson = Lesson()
        self.frame: Frame | None = None  # the frame the leaf is shown on (plan_frame)
        self.setWindowTitle("LeafStudio — lesson")
        self.setMinimumSize(*MINIMUM)
        self.setStyleSheet("background: white; color: #202020;")
        self.viewport = Viewport(self)
        self.viewport.show_bars = False  # the plan view has the step's colour bar, readable
        self.viewport.mesh_coloring = "height"  # as the plans of z(x) and of the mesh beside it
        self.viewport.iso_azimuths = (0.0,)  # from across the blade: its u runs as the plan's
        self.viewport.iso_elevations = ELEVATIONS
        self.title = QLabel()
        self.title.setFont(_font(TITLE_PT, bold=True))
        self.title.setWordWrap(True)
        self.plan = QLabel()
        self.plan.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.plan.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Ignored)
        self.caption = QLabel()
        self.caption.setFont(_font(CAPTION_PT))
        self.caption.setWordWrap(True)
        self.equation = QLabel()
        self.equation.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.equation.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        self.footer = QLabel()
        self.footer.setFont(_font(FOOTER_PT))
        self.footer.setStyleSheet("color: #606060;")
        self.footer.setWordWrap(True)
        self.text = QWidget()  # the column beside the leaf, TEXT_SHARE of the width
        column = QVBoxLayout(self.text)
        column.setContentsMargins(24, 16, 24, 12)
        column.setSpacing(10)
        column.addWidget(self.title)
        column.addWidget(self.plan, 1)
        column.addWidget(self.caption)
        column.addWidget(self.equation)
        column.addWidget(self.footer)
        row = QHBoxLayout(self)
        row.setContentsMargins(0, 0, 0, 0)
        row.setSpacing(0)
        row.addWidget(self.viewport, 1)
        row.addWidget(self.text)
        # the keys reach the lesson, never the 3D view (which would take them as VTK's)
        self.viewport.plotter.interactor.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        self.setFocusPolicy(Qt.FocusPolicy.StrongFocus)
        self._plan_timer = QTimer(self, singleShot=True, interval=120)
        self._plan_timer.timeout.connect(self._refit)
        window.result_shown.connect(self._on_result)
        # on screen here (the app's view may be covered): the result may be measured now
        self.viewport.rendered.connect(window.session.drawn)
        self._on_result()

    # --- steps ---------------------------------------------------------------------------------
    def go(self, index: int) -> None:
        """Show step `index` (clamped)."""
        self.lesson.go(index)
        self.show_step()

    def show_step(self) -> None:
        """The current step: its layers in the 3D view, its words, equation and plan."""
        step = self.lesson.step
        self.title.setText(step.title)
        self.caption.setText(step.words(bent=self._bent()))  # its steps run on the blade laid flat
        footer = self._footer_keys()
        result = self.window_.session.result
        if result is not None and not stretches(result):  # drawn as bent (view_aids.stretches)
            footer += "\n" + self._one_line(bent_notes(self.lesson.steps))
        self.footer.setText(footer)
        ratio = self.devicePixelRatioF()
        pixmap = QPixmap()  # empty for a step without one
        pixmap.loadFromData(equation_png(step.equation, dpi=self.logicalDpiY() * ratio))
        room = int(self._column_width() * ratio)
        if room > 0 and pixmap.width() > room:  # a long equation shrunk to fit, never cut
            pixmap = pixmap.scaledToWidth(room, Qt.TransformationMode.SmoothTransformation)
        pixmap.setDevicePixelRatio(ratio)
        self.equation.setPixmap(pixmap)
        self.equation.setVisible(not pixmap.isNull())
        if self.viewport.show_edges != step.edges:  # the mesh's triangles, where it says so
            self.viewport.set_edges(step.edges)
        layers = self._layers()
        for key in self.viewport.visible:  # the step's layers only
            on = key in layers
            if self.viewport.visible[key] != on:
                self.viewport.set_visible(key, on)
        self._stretch()
        self._fit_caption()
        self.text.layout().activate()  # the plan's room, with this step's words in place
        self._draw_plan()

    def _on_result(self, _outcome: object = None) -> None:
        """A result is shown in the app: the lesson shows it too, framed anew."""
        outcome = self.window_.session.shown.outcome
        if outcome is None:
            self.show_step()
            return
        result = outcome.result
        layers = self._layers()
        self.viewport.visible.update({key: key in layers for key in self.viewport.visible})
        # the plans' frame, so that the 3D view turns the leaf as the plan beside it, and both as
        # the app's view (its sketch's frame); a bent leaf's laid flat framed too
        self.frame = plan_frame(result, self.window_.session.view_frame())
        bounds = lesson_bounds(result, self.frame)
        self.viewport.show_layers(outcome.layers, self.frame, bounds, "reset")
        self.show_step()

    def _bent(self) -> bool:
        """Whether the session's result is a bent leaf's."""
        result = self.window_.session.result
        return result is not None and result.leaf.bend is not None

    def _layers(self) -> tuple[str, ...]:
        """The current step's layers (a bent leaf's laid flat where the step works flat)."""
        return step_layers(self.lesson.step, self._bent())

    def _stretch(self) -> None:
        """The relief exaggerated STRETCH times on every actor of the 3D view (a posed leaf's
        not: view_aids.stretches)."""
        matrix = stretch_matrix(self.window_.session.result, STRETCH)
        for actor in self.viewport.plotter.actors.values():
            if hasattr(actor, "SetUserMatrix"):
                actor.SetUserMatrix(matrix)
        self.viewport.redraw()

    def _column_width(self) -> int:
        """The text column's width inside its margins: the words' width."""
        margins = self.text.layout().contentsMargins()
        return self.text.width() - margins.left() - margins.right()

    def _footer_keys(self) -> str:
        """The footer's first line: the first of FOOTERS that fits the column (the last else)."""
        return self._one_line([keys.format(progress=self.lesson.progress()) for keys in FOOTERS])

    def _one_line(self, lines: Sequence[str]) -> str:
        """The first of `lines`, fullest first, that fits the column on one line in the
        footer's font (the last when none does)."""
        metrics, width = self.footer.fontMetrics(), self._column_width()
        return next((line for line in lines if metrics.horizontalAdvance(line) <= width), lines[-1])

    def _fit_caption(self) -> None:
        """The caption's words at the largest of CAPTION_STEPS that leaves the plan PLAN_LEAST
        of the column's height (the smallest where none does)."""
        column = self.text.layout()
        margins = column.contentsMargins()
        width = self._column_width()
        height = self.height() - margins.top() - margins.bottom()
        others = [self.title, self.equation, self.footer]
        fixed = sum(_label_height(label, width) for label in others if not label.isHidden())
        fixed += column.spacing() * (column.count() - 1)
        for points in CAPTION_STEPS:
            self.caption.setFont(_font(points))
            if height - fixed - _label_height(self.caption, width) >= PLAN_LEAST * height:
                break

    def _refit(self) -> None:
        self.viewport.camera("iso")
        self.show_step()  # the plan and the equation at the column's new size

    def _draw_plan(self) -> None:
        result = self.window_.session.result
        if result is None or self.plan.width() < 50:
            self.plan.clear()
            return
        ratio = self.devicePixelRatioF()
        size = (self.plan.width() * ratio, self.plan.height() * ratio)
        pixmap = QPixmap()
        dpi = self.logicalDpiX() * ratio
        pixmap.loadFromData(plan_png(result, self.lesson.index, size, dpi, frame=self.frame))
        pixmap.setDevicePixelRatio(ratio)
        self.plan.setPixmap(pixmap)

    # --- window --------------------------------------------------------------------------------
    def keyPressEvent(self, event: QKeyEvent) -> None:
        """→, space, page down: next; ←, backspace, page up: back; Home, End; Esc leaves."""
        key = event.key()
        if key in NEXT_KEYS or key in BACK_KEYS:
            moved = self.lesson.next() if key in NEXT_KEYS else self.lesson.back()
            if moved:
                self.show_step()
        elif key in (Qt.Key.Key_Home, Qt.Key.Key_End):
            self.go(0 if key == Qt.Key.Key_Home else len(self.lesson.steps) - 1)
        elif key == Qt.Key.Key_Escape:
            self.close()
        else:
            super().keyPressEvent(event)

    def resizeEvent(self, event: QResizeEvent) -> None:
        super().resizeEvent(event)
        self.text.setFixedWidth(int(TEXT_SHARE * self.width()))
        self._plan_timer.start()  # plan and camera fitted again once resizing rests

    def grab_all(self) -> QPixmap:
        """The lesson as on screen, with the 3D view from its own frame buffer (a native
        window: Qt's grab leaves it blank)."""
        if self._plan_timer.isActive():
            self._plan_timer.stop()
            self._refit()
        pixmap = self.grab()
        painter = QPainter(pixmap)
        corner = self.viewport.mapTo(self, QPoint(0, 0))
        painter.drawImage(QRect(corner, self.viewport.size()), self.viewport.image())
        painter.end()
        return pixmap

    def closeEvent(self, event: QCloseEvent) -> None:
        with contextlib.suppress(RuntimeError, TypeError):
            self.window_.result_shown.disconnect(self._on_result)
        self.viewport.close_plotter()
        event.accept()


def open_lesson(window) -> LessonWindow:
    """Open the lesson over `window`, full screen (one at a time: an open one is raised)."""
    lesson = getattr(window, "lesson_window", None)
    if lesson is None or not lesson.isVisible():
        lesson = window.lesson_window = LessonWindow(window)
    screen = window.screen() or QGuiApplication.primaryScreen()
    lesson.setGeometry(screen.geometry())  # the whole screen, even where no window manager
    lesson.showFullScreen()  # honours full screen (a bare X server, a test's display)
    lesson.raise_()
    lesson.activateWindow()
    lesson.setFocus()
    return lesson


LESSON_ACTIONS = (
    Action(
        "view.lesson",
        "View",
        "&Lesson",
        open_lesson,
        shortcut="F5",
        tooltip="The method one step per screen, for a class: the 3D leaf, a plan view, the "
        "step in plain words and its equation. Arrow keys or space to move, Esc to leave.",
    ),
)
