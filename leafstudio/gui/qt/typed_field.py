"""A slider's number, typed into: a line edit in place of superqt's label (hidden), which clamps
what is typed to the slider's range without a word (a typed fold of 90 bent the leaf 75°). The
parameter panel's sliders (controls.py) and the bend sliders (bend_sliders.py) each take one,
over a declared `paramspec.Ranged`: a value its `parse` takes is set on the slider, widened to
hold it; one it refuses is not, the value in force shown again, and `refused` says why.
Only superqt's public API is used (`setEdgeLabelMode(NoLabel)` hides its label).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import QLineEdit
from superqt import QLabeledSlider

from leafstudio.errors import LeafError
from leafstudio.paramspec import Ranged, Real


def shown_text(param: Ranged, value: Any) -> str:
    """A slider's value as its field shows it: `decimals` places, or 3 significant digits for a
    value too small for them (a project's tolerance of 1e-6)."""
    if isinstance(param, Real):
        value = float(value)
        if value == 0 or abs(value) >= 10.0**-param.decimals:
            return f"{value:.{param.decimals}f}"
        return f"{value:.3g}"
    return str(int(value))


def refusal(param: Ranged, exc: LeafError, kept: str) -> str:
    """Why a typed value was not taken: the parameter's message, the value kept and, unless the
    message says it, what the parameter takes."""
    said = str(exc)
    takes = "between" not in said or getattr(param, "special", None) is not None
    also = f" It takes {param.describe()}." if takes else ""
    return f"{said}; {param.what} stays {kept}.{also}"


class TypedField(QLineEdit):
    """The number of `slider` (superqt's, over `param`), typed into; wide enough for any value
    `param` takes. `take(value)` may take a parsed value itself (K's word "auto": its box
    checked) and say so with True; else the slider is set to it."""

    refused = Signal(str)  # why a typed value was not taken; "" when one was

    def __init__(
        self,
        slider: QLabeledSlider,
        param: Ranged,
        take: Callable[[Any], bool] | None = None,
    ) -> None:
        super().__init__()
        self.slider, self.param, self._take = slider, param, take
        slider.setEdgeLabelMode(QLabeledSlider.EdgeLabelMode.NoLabel)
        self.setAlignment(Qt.AlignmentFlag.AlignRight)
        values = (param.low, param.high, *param.panel_range)
        longest = max(len(shown_text(param, v)) for v in values)
        self.setFixedWidth(self.fontMetrics().horizontalAdvance("8" * (longest + 1)) + 12)
        self.setToolTip(param.help_text())
        slider.layout().addWidget(self)
        slider.valueChanged.connect(lambda *_: self.show_value())
        self.editingFinished.connect(self._typed)
        self.show_value()

    def shown(self) -> str:
        """The slider's value as the field shows it."""
        return shown_text(self.param, self.slider.value())

    def show_value(self) -> None:
        """Show the slider's value (typing not applied is dropped)."""
        self.setText(self.shown())

    def _typed(self) -> None:
        """A value typed: set on the slider (widened to hold it) when `param` takes it, else
        refused with its message and the value in force shown again."""
        text, kept = self.text().strip(), self.shown()
        if text == kept:
            return  # left as shown (a project's or a pose's exact value stays)
        try:
            value = self.param.parse(text)
        except LeafError as exc:
            self.show_value()
            self.refused.emit(refusal(self.param, exc, kept))
            return
        self.refused.emit("")
        if self._take is None or not self._take(value):
            low, high = self.slider.minimum(), self.slider.maximum()
            if not low <= value <= high:
                self.slider.setRange(min(low, value), max(high, value))
            self.slider.setValue(value)
        self.show_value()
