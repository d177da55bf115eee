"""The status bar's line of text, painted without a layout pass, and the progress of a file
being read, with Cancel (Busy).

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
    QProgressBar,
    QPushButton,
    QSizePolicy,
    QWidget,
)


class StatusText(QWidget):
    """A one-line text, elided at the right when too long; `setText`/`text` as a QLabel's, and
    its colour from the palette (a style sheet's `color` applies)."""

    def __init__(self, text: str = "", parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._text = text
        self._tip = ""
        self.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Fixed)

    def text(self) -> str:
        return self._text

    def setText(self, text: str, tip: str = "") -> None:
        """Show `text`; the tooltip is the whole line, then `tip` (details that would not fit),
        which a text that extends the line before it (a note added at its end) keeps."""
        if text != self._text or tip:
            if not tip and self._text and text.startswith(self._text):
                tip = self._tip
            self._text, self._tip = text, tip
            self.setToolTip(f"{text}\n{tip}" if tip else text)
            self.update()

    def sizeHint(self) -> QSize:
        return QSize(0, self.fontMetrics().height() + 2)

    def minimumSizeHint(self) -> QSize:
        return self.sizeHint()

    def paintEvent(self, event: QPaintEvent) -> None:
        painter = QPainter(self)
        painter.setPen(self.palette().color(QPalette.ColorRole.WindowText))
        line = self.fontMetrics().elidedText(self._text, Qt.TextElideMode.ElideRight, self.width())
        painter.drawText(
            self.rect(), Qt.AlignmentFlag.AlignVCenter | Qt.AlignmentFlag.AlignLeft, line
        )


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
