"""The parameter panel: one labelled control per Params field, made from its declaration
(model.PARAMS: widget kind, range, label and tooltip).

A number with a slider range (paramspec.Ranged.slider) gets a slider over that range, which sits
inside the valid one, so the panel never offers a value Params refuses. A value outside it that a
project holds widens that slider to show it, and every value the user has not touched is given
back exactly as it was shown (`params()`), so no valid value is clamped or rounded away.

A slider's number is a field of our own (`fields`: typed_field.TypedField, as the bend sliders'),
not superqt's label, which clamps what is typed to the slider's range: a typed value that Params
takes widens the slider as a project's value does, and one it refuses is not applied, with
Params' message under the controls (`note`).

Every change emits `changed(Params)`, throttled so that a slider drag does not flood the worker:
the first value goes out at once and the last value always follows. `released` marks the end of
a slider drag (one undo step per drag: `is_dragging()` is True until then).
"""

from __future__ import annotations

from typing import Any

from PySide6.QtCore import QEvent, QKeyCombination, QObject, Qt, Signal
from PySide6.QtGui import QKeySequence, QValidator
from PySide6.QtWidgets import QCheckBox, QComboBox, QFormLayout, QLabel, QLineEdit, QWidget
from superqt import QLabeledDoubleSlider, QLabeledSlider, QLargeIntSpinBox
from superqt.utils import qthrottled

from leafstudio.errors import LeafError
from leafstudio.gui.qt.typed_field import TypedField, refusal
from leafstudio.model import PARAMS, Params
from leafstudio.paramspec import Choice, Param, Ranged, Real, Switch, Whole, read_whole

THROTTLE_MS = 80
NOTE_COLOR = "#b00020"  # as the status line's failures


class _WholeText(QValidator):
    """Lets into the Seed box only what `read_whole` reads (digits with an optional sign) and a
    bare sign on the way to one. superqt's own validator also lets in `--5`, `½` and `²`, which
    its bare int() cannot read: with keyboard tracking off that int() ran inside Qt's stepBy,
    and the ValueError killed the app (segfault)."""

    def validate(self, text: str, pos: int) -> tuple[QValidator.State, str, int]:
        if read_whole(text) is not None:
            return QValidator.State.Acceptable, text, pos
        if text.strip() in ("", "+", "-"):
            return QValidator.State.Intermediate, text, pos
        return QValidator.State.Invalid, text, pos


class WholeBox(QLargeIntSpinBox):
    """A whole number over its parameter's whole range (a QSpinBox stops at 2**31 - 1). What is
    typed is read on Return, on leaving the box, and before a step (Up/Down, Page Up/Down, the
    wheel, the arrows), never per keystroke (keyboard tracking clamped each one), and is checked
    by the declaration first: superqt's box would clamp a seed of -5 to 0; here it is refused,
    and a step is not taken from it (`verdict` carries why; "" when the typed value is taken).
    So superqt's int() only ever reads text Params took, or the value kept."""

    verdict = Signal(str)

    def __init__(self, param: Whole) -> None:
        super().__init__()
        self.param = param
        self.setRange(param.low, param.high)
        self.setKeyboardTracking(False)
        self.lineEdit().setValidator(_WholeText(self))

    def _check_typed(self) -> bool:
        """Take or refuse the typed text; False when it was refused (the kept value shown)."""
        text = self.lineEdit().text().strip()
        if text == str(self.value()):
            return True
        try:
            self.param.parse(text)
        except LeafError as exc:
            self.lineEdit().setText(str(self.value()))  # superqt then reads the value kept
            self.verdict.emit(refusal(self.param, exc, str(self.value())))
            return False
        self.verdict.emit("")
        return True

    def stepBy(self, steps: int) -> None:
        """Every step (keys, wheel, arrows) comes here: from a typed value Params takes, or not
        at all when the typed value is refused."""
        if self._check_typed():
            super().stepBy(steps)

    def keyPressEvent(self, event: Any) -> None:
        if event.key() in (Qt.Key.Key_Return, Qt.Key.Key_Enter):
            self._check_typed()
        super().keyPressEvent(event)

    def focusOutEvent(self, event: Any) -> None:
        self._check_typed()
        super().focusOutEvent(event)

    def closeEvent(self, event: Any) -> None:
        self._check_typed()  # superqt reads pending text here too
        super().closeEvent(event)


def _widget(param: Param) -> QWidget:
    """The control for one declared parameter, over its panel range."""
    if isinstance(param, Switch):
        return QCheckBox(param.label)
    if isinstance(param, Choice):
        combo = QComboBox()
        combo.addItems(param.choices)
        return combo
    if isinstance(param, Whole) and param.slider is None:
        return WholeBox(param)
    if isinstance(param, Real):
        slider = QLabeledDoubleSlider(Qt.Orientation.Horizontal)
        slider.setDecimals(param.decimals)
    else:
        assert isinstance(param, Whole)
        slider = QLabeledSlider(Qt.Orientation.Horizontal)
        slider.setSingleStep(param.step)
        slider.setPageStep(4 * param.step)
    slider.setRange(*param.panel_range)
    return slider


def _is_slider(widget: QWidget) -> bool:
    return isinstance(widget, QLabeledSlider)  # QLabeledDoubleSlider is one too


REDO = (  # the Edit menu's other Redo keys (actions.py)
    QKeyCombination(
        Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier, Qt.Key.Key_Z
    ),
    QKeyCombination(Qt.KeyboardModifier.ControlModifier, Qt.Key.Key_Y),
)


class _UndoToWindow(QObject):
    """Undo and Redo pressed in a field with nothing of its own to undo or redo (a value
    typed and applied with Return: the field was set afresh) go to the window's Edit menu, not
    to the field, which would take the keys and do nothing; typing not yet applied is still
    undone in the field."""

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if event.type() == QEvent.Type.ShortcutOverride and isinstance(watched, QLineEdit):
            if event.matches(QKeySequence.StandardKey.Undo):
                return not watched.isUndoAvailable()  # filtered: left to the window
            if event.matches(QKeySequence.StandardKey.Redo) or event.keyCombination() in REDO:
                return not watched.isRedoAvailable()
        return False


class ParamPanel(QWidget):
    """Labelled sliders, spin boxes and choices for Params; `params()` reads them all."""

    changed = Signal(object)  # Params
    released = Signal()  # a slider was let go

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        form = QFormLayout(self)
        form.setFieldGrowthPolicy(QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)
        self.widgets: dict[str, QWidget] = {}
        self.specials: dict[str, QCheckBox] = {}  # a word a number also takes (K's "auto")
        self.fields: dict[str, TypedField] = {}  # a slider's number, typed into
        for name, param in PARAMS.items():
            widget = self.widgets[name] = _widget(param)
            setattr(self, name, widget)
            widget.setToolTip(param.help_text())
            form.addRow("" if isinstance(param, Switch) else param.label, widget)
            if not isinstance(param, Switch):
                form.labelForField(widget).setToolTip(param.help_text())
            if isinstance(param, Whole) and param.special:
                box = self.specials[name] = QCheckBox(param.special.capitalize())
                box.setToolTip(param.help_text())
                form.addRow("", box)
                box.toggled.connect(self._on_edit)
            self._connect(widget)
            if _is_slider(widget):
                self._add_field(name, widget, param)
            elif isinstance(widget, WholeBox):
                widget.verdict.connect(self.say)
        widest = max((f.width() for f in self.fields.values()), default=0)
        for field in self.fields.values():  # the sliders line up
            field.setFixedWidth(widest)
        self.note = QLabel()  # why a typed value was refused; hidden when none was
        self.note.setWordWrap(True)
        self.note.setStyleSheet(f"color: {NOTE_COLOR}")
        self.note.hide()
        form.addRow(self.note)
        self.auto_k = self.specials["k"]
        self._undo_to_window = _UndoToWindow(self)
        for edit in self.findChildren(QLineEdit):  # the fields and the spin boxes' own
            edit.installEventFilter(self._undo_to_window)
        self._emit_throttled = qthrottled(self._emit, timeout=THROTTLE_MS, leading=True)
        self._shown = Params()
        self._shown_values: dict[str, Any] = {}
        self.set_params(self._shown)

    def _connect(self, widget: QWidget) -> None:
        if isinstance(widget, QCheckBox):
            widget.toggled.connect(self._on_edit)
        elif isinstance(widget, QComboBox):
            widget.currentTextChanged.connect(self._on_edit)
        else:
            widget.valueChanged.connect(self._on_edit)
        if _is_slider(widget):
            widget.sliderReleased.connect(self.released)

    def _add_field(self, name: str, slider: QLabeledSlider, param: Ranged) -> None:
        field = self.fields[name] = TypedField(slider, param, lambda v: self._special(name, v))
        field.refused.connect(self.say)

    def _show_field(self, name: str) -> None:
        self.fields[name].show_value()

    def _special(self, name: str, value: Any) -> bool:
        """A typed value that is its parameter's word (K's "auto"): its box checked. A number
        with its word on is never typed: the field is disabled with its slider."""
        if name not in self.specials or value != getattr(PARAMS[name], "special", None):
            return False
        self.specials[name].setChecked(True)
        return True

    def say(self, text: str) -> None:
        """Show `text` under the controls (why a typed value was refused); none hides it."""
        self.note.setText(text)
        self.note.setVisible(bool(text))

    def is_dragging(self) -> bool:
        """True while a slider is held down."""
        return any(_is_slider(w) and w.isSliderDown() for w in self.widgets.values())

    def _read(self) -> dict[str, Any]:
        """Each control's value as the panel reads it."""
        values: dict[str, Any] = {}
        for name, param in PARAMS.items():
            widget = self.widgets[name]
            if name in self.specials and self.specials[name].isChecked():
                values[name] = param.special  # type: ignore[attr-defined]
            elif isinstance(widget, QCheckBox):
                values[name] = widget.isChecked()
            elif isinstance(widget, QComboBox):
                values[name] = widget.currentText()
            elif isinstance(param, Real):
                values[name] = round(float(widget.value()), param.decimals + 2)
            else:
                values[name] = int(widget.value())
        return values

    def params(self) -> Params:
        """The Params the controls show: a value the user has not changed since `set_params`
        is the one given there, exactly."""
        read = self._read()
        return Params(
            **{
                name: getattr(self._shown, name) if value == self._shown_values[name] else value
                for name, value in read.items()
            }
        )

    def set_params(self, params: Params) -> None:
        """Show `params` without emitting `changed`; a slider widens to show a value outside
        its range (declared or not, it is valid: Params checked it)."""
        widgets = [*self.widgets.values(), *self.specials.values()]
        blocked = [w.blockSignals(True) for w in widgets]
        try:
            for name, param in PARAMS.items():
                self._show(name, param, getattr(params, name))
        finally:
            for widget, was in zip(widgets, blocked, strict=True):
                widget.blockSignals(was)
        self._shown, self._shown_values = params, self._read()
        self._sync_enabled()
        self.say("")  # a refusal concerned the values shown before

    def _show(self, name: str, param: Param, value: Any) -> None:
        widget = self.widgets[name]
        if name in self.specials:
            self.specials[name].setChecked(value == param.special)  # type: ignore[attr-defined]
            if self.specials[name].isChecked():
                if name in self.fields:  # text typed, not applied, is dropped before it is read
                    self._show_field(name)
                return
        if isinstance(widget, QCheckBox):
            widget.setChecked(value)
        elif isinstance(widget, QComboBox):
            widget.setCurrentText(value)
        else:
            if _is_slider(widget) and isinstance(param, Ranged):
                low, high = param.panel_range
                widget.setRange(min(low, value), max(high, value))
            widget.setValue(value)
            if name in self.fields:
                self._show_field(name)

    def _sync_enabled(self) -> None:
        self.k.setEnabled(not self.auto_k.isChecked())
        self.radius_factor.setEnabled(self.mesher.currentText() == "bpa")

    def _on_edit(self, *_: object) -> None:
        self._sync_enabled()
        self._emit_throttled()

    def _emit(self) -> None:
        self.changed.emit(self.params())
