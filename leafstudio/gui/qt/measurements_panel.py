"""The Measurements dock: the shown result's table (gui/model/measurements.py makes its rows),
with the whole table out of the app: Copy (Ctrl+C, the button, the context menu) puts it on the
clipboard as text, Save writes it as CSV or JSON. Section titles span both columns, so they show
whole in the dock's width, and every cell's tooltip holds its whole text.
"""

from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QAction, QGuiApplication, QKeyEvent, QKeySequence
from PySide6.QtWidgets import (
    QFileDialog,
    QHBoxLayout,
    QHeaderView,
    QPushButton,
    QTreeWidget,
    QTreeWidgetItem,
    QVBoxLayout,
    QWidget,
)

from leafstudio.errors import LeafError
from leafstudio.gui.model.measurements import Sections, save_sections, sections_text

FILTERS = "CSV table (*.csv);;JSON (*.json)"


class MeasurementTree(QTreeWidget):
    """The table; Ctrl+C copies all of it (a tree's own copy takes the current cell only)."""

    copy_all = Signal()

    def keyPressEvent(self, event: QKeyEvent) -> None:
        if event.matches(QKeySequence.StandardKey.Copy):
            self.copy_all.emit()
            event.accept()
            return
        super().keyPressEvent(event)


class MeasurementsPanel(QWidget):
    """The table (`tree`) with Copy and Save buttons.

    Signals
    -------
    saved(str)
        The table was written to this file.
    failed(str, str)
        A save failed: the title and the one-line message for the window to show.
    """

    saved = Signal(str)
    failed = Signal(str, str)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.sections: Sections = []
        self.tree = MeasurementTree()
        self.tree.setHeaderLabels(["Measure", "Value"])
        self.tree.setColumnWidth(0, 190)
        self.tree.header().setSectionResizeMode(0, QHeaderView.ResizeMode.Stretch)
        self.tree.header().setSectionResizeMode(1, QHeaderView.ResizeMode.ResizeToContents)
        self.tree.header().setStretchLastSection(False)
        self.tree.copy_all.connect(self.copy)
        self.copy_button = QPushButton("Copy")
        self.copy_button.setToolTip("Copy the whole table as text (Ctrl+C)")
        self.copy_button.clicked.connect(self.copy)
        self.save_button = QPushButton("Save…")
        self.save_button.setToolTip("Save the table as CSV or JSON")
        self.save_button.clicked.connect(self.save_dialog)
        self.tree.setContextMenuPolicy(Qt.ContextMenuPolicy.ActionsContextMenu)
        for title, slot in (("Copy table", self.copy), ("Save table…", self.save_dialog)):
            action = QAction(title, self.tree)
            action.triggered.connect(slot)
            self.tree.addAction(action)
        buttons = QHBoxLayout()
        buttons.addWidget(self.copy_button)
        buttons.addWidget(self.save_button)
        buttons.addStretch(1)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.tree)
        layout.addLayout(buttons)
        self._enable()

    def show_sections(self, sections: Sections) -> None:
        """Fill the table: a title row spanning both columns per section, then its rows."""
        self.sections = list(sections)
        tree = self.tree
        tree.setUpdatesEnabled(False)
        tree.clear()
        for title, rows in self.sections:
            section = QTreeWidgetItem([title, ""])
            section.setToolTip(0, title)
            for label, value in rows:
                item = QTreeWidgetItem([label, value])
                item.setToolTip(0, label)
                item.setToolTip(1, value)
                section.addChild(item)
            tree.addTopLevelItem(section)
            section.setFirstColumnSpanned(True)
            section.setExpanded(True)
        tree.setUpdatesEnabled(True)
        self._enable()

    def clear(self) -> None:
        self.sections = []
        self.tree.clear()
        self._enable()

    def _enable(self) -> None:
        for widget in (self.copy_button, self.save_button):
            widget.setEnabled(bool(self.sections))

    def text(self) -> str:
        """The whole table as Copy puts it on the clipboard ("" when empty)."""
        return sections_text(self.sections) if self.sections else ""

    def copy(self) -> None:
        """Put the whole table on the clipboard as text."""
        if self.sections:
            QGuiApplication.clipboard().setText(self.text())

    def save_dialog(self) -> None:
        """Ask for a file and save the table there (CSV or JSON by its suffix)."""
        if not self.sections:
            return
        path, chosen = QFileDialog.getSaveFileName(self, "Save the measurements", "", FILTERS)
        if not path:
            return
        if not path.lower().endswith((".csv", ".json")):
            path += ".json" if "JSON" in chosen else ".csv"
        self.save(path)

    def save(self, path: str) -> bool:
        """Write the table to `path`; a failure is reported (`failed`), never raised."""
        try:
            save_sections(path, self.sections)
        except LeafError as exc:
            self.failed.emit("Cannot save the measurements", str(exc))
            return False
        self.saved.emit(path)
        return True
