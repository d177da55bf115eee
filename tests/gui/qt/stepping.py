"""Stepping a spin box as a user does, for test_controls.py and the child process it starts
(SEED_STEPS_SCRIPT): a module of its own, so that the child imports Qt and the panel only, not
the window and the pipeline."""

from __future__ import annotations

from PySide6.QtCore import QPoint, QPointF, Qt
from PySide6.QtGui import QWheelEvent
from PySide6.QtWidgets import QApplication, QStyle, QStyleOptionSpinBox


def step(qtbot, box, how: str) -> None:
    """Step the box as a user does: a key, the mouse wheel, or a click on its up arrow (or
    press Return: "return")."""
    if how == "return":
        qtbot.keyClick(box, Qt.Key.Key_Return)
    elif how in ("up", "page up"):
        qtbot.keyClick(box, Qt.Key.Key_Up if how == "up" else Qt.Key.Key_PageUp)
    elif how == "wheel":
        centre = QPointF(box.rect().center())
        wheel = QWheelEvent(
            centre,
            QPointF(box.mapToGlobal(box.rect().center())),
            QPoint(),
            QPoint(0, 120),
            Qt.MouseButton.NoButton,
            Qt.KeyboardModifier.NoModifier,
            Qt.ScrollPhase.NoScrollPhase,
            False,
        )
        QApplication.sendEvent(box, wheel)
    else:
        option = QStyleOptionSpinBox()
        box.initStyleOption(option)
        control = QStyle.ComplexControl.CC_SpinBox
        up = box.style().subControlRect(control, option, QStyle.SubControl.SC_SpinBoxUp, box)
        qtbot.mouseClick(box, Qt.MouseButton.LeftButton, pos=up.center())


STEPS = ("up", "page up", "wheel", "arrow")  # Page Up: 10 steps
