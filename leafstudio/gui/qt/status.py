"""The status bar's line of text, painted without a layout pass, the count of its notes
(NotesButton), and the progress of a file being read, with Cancel (Busy).

A QLabel asks its layout for new geometry at every `setText`: the status bar is laid out again
and the main window repaints once more a moment later. In a window holding the 3D view (a
QOpenGLWidget), every repaint composes the whole window with OpenGL, in software here: that
second repaint cost as much as a render of the 3D view after each result. This widget takes the
status bar's width and one line's height, and repaints only itself when its text changes.
"""

from __future__ import annotations

import time

from PySide6.QtCore import QSize, Qt, QTimer, Signal
from PySide6.QtGui import QPainter, QPaintEvent, QPalette
from PySide6.QtWidgets import (
    QHBoxLayout,
    QLabel,
    QMessageBox,
    QProgressBar,
    QPushButton,
    QSizePolicy,
    QToolButton,
    QWidget,
)

from leafstudio.gui.model.status_line import StatusLine, bullets, said


class StatusText(QWidget):
    """A one-line text, elided at the right when too long; `setText`/`text` as a QLabel's, and
    its colour from the palette (a style sheet's `color` applies). A result's line comes in
    parts (`show_line`: gui/model/status_line.py): its head, then its first note (its headline
    where the whole does not fit: `shown_text`), every note in the tooltip; `line_changed`
    tells the notes button (NotesButton)."""

    line_changed = Signal(object)  # the StatusLine shown

    def __init__(self, text: str = "", parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._line = StatusLine(text)
        self.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Fixed)

    def text(self) -> str:
        return self._line.text

    def line(self) -> StatusLine:
        return self._line

    def setText(self, text: str, tip: str = "") -> None:
        """Show `text`, with no notes; the tooltip is the text, then `tip` (details that would
        not fit)."""
        self.show_line(StatusLine(text, details=tip))

    def show_line(self, line: StatusLine) -> None:
        """Show `line` (repainted only when it changed)."""
        if line != self._line:
            self._line = line
            self.setToolTip(line.tip)
            self.update()
            self.line_changed.emit(line)

    def add_note(self, note: str) -> None:
        """A note on what the line says (said once), after those it has."""
        self.show_line(self._line.noted(note))

    def extend(self, more: str) -> None:
        """`more` after the line's head, before its notes (the measuring time)."""
        self.show_line(self._line.extended(more))

    def sizeHint(self) -> QSize:
        return QSize(0, self.fontMetrics().height() + 2)

    def minimumSizeHint(self) -> QSize:
        return self.sizeHint()

    def shown_text(self) -> str:
        """The line as painted at the widget's width: the whole line, or the head and the first
        note's headline (StatusLine.fitted), cut with "…" only if even that is too long."""
        metrics, width = self.fontMetrics(), self.width()
        text = self._line.fitted(lambda text: metrics.horizontalAdvance(text) <= width)
        return metrics.elidedText(text, Qt.TextElideMode.ElideRight, width)

    def paintEvent(self, event: QPaintEvent) -> None:
        painter = QPainter(self)
        painter.setPen(self.palette().color(QPalette.ColorRole.WindowText))
        line = self.shown_text()
        painter.drawText(
            self.rect(), Qt.AlignmentFlag.AlignVCenter | Qt.AlignmentFlag.AlignLeft, line
        )


class NotesButton(QToolButton):
    """How many notes the status line has ("3 notes"), at the status bar's right, as napari
    counts its notifications there; hidden without any. Its tooltip lists them whole, and a
    click shows them in a box (the line shows the first, cut to its width)."""

    def __init__(self, status: StatusText, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setAutoRaise(True)
        # the status line's height: a taller button, shown, grew the status bar a pixel and
        # the sketch view above it re-fitted its drawing (test_drawing.py)
        self.setFixedHeight(status.sizeHint().height())
        self._notes: tuple[str, ...] = ()
        self.box: QMessageBox | None = None  # the last box shown (tests read it)
        status.line_changed.connect(self._show)
        self.clicked.connect(self._open)
        self.hide()

    def _show(self, line: StatusLine) -> None:
        self._notes = line.notes
        self.setText(f"⚠ {line.count}" if line.notes else "")
        self.setToolTip(bullets(line.notes))
        self.setVisible(bool(line.notes))

    def _open(self) -> None:
        """The notes whole, in a box that does not hold up the window."""
        box = QMessageBox(QMessageBox.Icon.Information, "Notes", "", parent=self.window())
        box.setText("\n\n".join(said(note) for note in self._notes))
        box.setWindowModality(Qt.WindowModality.NonModal)
        box.open()
        self.box = box


class Busy(QWidget):
    """The status bar's progress while a file opens (read, then its first reconstruction): the
    fraction read when the reader tells it (`progress`), else a busy bar; what is being done,
    the seconds so far and Cancel. Hidden when idle; `start(text)` shows it, `stop()` hides it."""

    cancelled = Signal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.bar = QProgressBar()
        self.bar.setRange(0, 0)  # how long a read takes is not known: a busy bar
        self.bar.setMaximumWidth(120)
        self.bar.setTextVisible(False)
        self.seconds = QLabel()
        self.button = QPushButton("Cancel")
        self.button.setToolTip("Stop opening this file; the current leaf stays")
        self.button.clicked.connect(self.cancelled)
        layout = QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        for widget in (self.bar, self.seconds, self.button):
            layout.addWidget(widget)
        self._clock = QTimer(self)
        self._clock.setInterval(1000)
        self._clock.timeout.connect(self._tick)
        self._start = 0.0
        self._doing = ""
        self.hide()

    def start(self, what: str) -> None:
        self._start = time.monotonic()
        self.setToolTip(what)
        self.bar.setRange(0, 0)
        self._doing = "reading"
        self._tick()
        self._clock.start()
        self.show()

    def progress(self, fraction: float | None, doing: str) -> None:
        """`fraction` of `doing` is done (None: not known, a busy bar)."""
        if fraction is None:
            self.bar.setRange(0, 0)
            self._doing = doing
        else:
            self.bar.setRange(0, 1000)
            self.bar.setValue(round(1000 * fraction))
            self._doing = f"{doing} {100 * fraction:.0f}%"
        self._tick()

    def stop(self) -> None:
        self._clock.stop()
        self.hide()

    def _tick(self) -> None:
        self.seconds.setText(f"{self._doing} · {time.monotonic() - self._start:.0f} s")
