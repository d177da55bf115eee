"""The window on a small screen (a projector at 1280x720 or 1024x768): the docks collapse into
one column of tabs beside the 3D view instead of squeezing it, and spread back out when the
window is wide again.

Below COMPACT_WIDTH every docked (not floating) dock becomes a tab of one column on the left,
Parameters in front, the column about a third of the window wide, so the 3D view keeps at least
half the width and every panel its whole text. The layout the window had before (the user's own
arrangement, or the first start's) comes back above SPREAD_WIDTH; the two widths differ so a
window dragged about the threshold does not flip at every pixel.
"""

from __future__ import annotations

from PySide6.QtCore import QByteArray, QEvent, QObject, Qt, QTimer
from PySide6.QtWidgets import QDockWidget, QFrame, QMainWindow, QScrollArea, QStyle, QWidget

COMPACT_WIDTH = 1400  # pixels: narrower than this, the docks are tabs of one column
SPREAD_WIDTH = 1450  # pixels: wider than this, the wide layout comes back
COLUMN_SHARE = 0.34  # the tabs' column: this share of the window's width
COLUMN_MIN = 390  # pixels: room for the sketch editor's tool rows
FRONT = "Parameters"  # the tab in front once collapsed
LEFT = Qt.DockWidgetArea.LeftDockWidgetArea


class DockLayout(QObject):
    """Watches the window's size and collapses or spreads its docks (see the module's text)."""

    def __init__(self, window: QMainWindow) -> None:
        super().__init__(window)
        self.window_ = window
        self.wide_state: QByteArray = window.saveState()  # the first start's layout
        self._pending = False
        window.installEventFilter(self)

    def docks(self) -> list[QDockWidget]:
        """The window's docks that sit in it (floating ones are left where they are)."""
        return [d for d in self.window_.docks.values() if not d.isFloating()]

    def is_compact(self) -> bool:
        """Whether the docks already are the tabs of one column."""
        docks = [d for d in self.docks() if not d.isHidden()]
        if len(docks) < 2:
            return True
        tabs = set(self.window_.tabifiedDockWidgets(docks[0])) | {docks[0]}
        return all(d in tabs for d in docks)

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if watched is self.window_ and event.type() == QEvent.Type.Resize and not self._pending:
            self._pending = True  # once the resize is over: a relayout inside it is undone
            QTimer.singleShot(0, self.fit)
        return False

    def fit(self) -> None:
        """Collapse or spread the docks for the window's width now."""
        self._pending = False
        width = self.window_.width()
        if width < COMPACT_WIDTH and not self.is_compact():
            self.collapse()
        elif width > SPREAD_WIDTH and self.is_compact() and self.wide_state is not None:
            self.window_.restoreState(self.wide_state)

    def collapse(self) -> None:
        """Every docked dock a tab of one column on the left, FRONT in front."""
        window = self.window_
        self.wide_state = window.saveState()
        docks = self.docks()
        shown = {d: not d.isHidden() for d in docks}
        for dock in docks:
            window.addDockWidget(LEFT, dock)
        for dock in docks[1:]:
            window.tabifyDockWidget(docks[0], dock)
        for dock, on in shown.items():
            dock.setVisible(on)
        front = window.docks.get(FRONT)
        if front is not None:
            front.raise_()
        window.resizeDocks(docks[:1], [self.column_width(docks)], Qt.Orientation.Horizontal)

    def column_width(self, docks: list[QDockWidget]) -> int:
        """The tabs' column: a third of the window, wide enough for every tab's whole title,
        never more than half the window (the 3D view's share)."""
        window = self.window_
        space = window.style().pixelMetric(QStyle.PixelMetric.PM_TabBarTabHSpace)
        metrics = window.fontMetrics()
        tabs = sum(metrics.horizontalAdvance(d.windowTitle()) + space + 4 for d in docks)
        wanted = max(COLUMN_MIN, int(COLUMN_SHARE * window.width()), tabs + 8)
        return min(wanted, window.width() // 2)


def scrolled(widget: QWidget) -> QScrollArea:
    """`widget` in a frameless scroll area that keeps its width: a dock holding it can be
    shorter than the widget (a projector's 720 px) without squeezing its rows."""
    area = QScrollArea()
    area.setFrameShape(QFrame.Shape.NoFrame)
    area.setWidgetResizable(True)
    area.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
    area.setWidget(widget)
    area.setMinimumWidth(
        widget.minimumSizeHint().width() + area.verticalScrollBar().sizeHint().width()
    )
    return area


def install(window: QMainWindow) -> DockLayout:
    """Watch `window` (a MainWindow with its docks added) and fit its docks to its width."""
    return DockLayout(window)
