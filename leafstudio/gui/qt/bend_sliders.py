"""The Fold, Curl, Roll and Twist sliders in the Parameters panel, under K and the grid (issue 21,
build item 6): they bend the document's leaf live through `Session.set_bend`
(gui/model/bending.py), one undo step per drag; undo, a new document or an opened project
shows its pose on them.

Fold is the angle each half turns up about the midrib (as a form's), widths kept; curl bends
the midrib on a circle of radius 1 / (2 curl) from the base, its length kept (z = curl · x²
near the base: a leaf of length 1 curled 0.5 lifts its apex 0.46, curled 1 turns it 115°);
roll bends each cross-section into an arc of radius 1 / roll, widths kept; twist turns each
cross-section about the midrib by twist · x radians. The range is the Forms dock's: a fold of
±75°, a curl of ±1; a roll of ±20 closes a blade 0.16 wide into a tube; a twist of ±3.1 turns
the apex half a turn.
"""

from __future__ import annotations

from typing import Any

from PySide6.QtCore import QObject, Qt, Signal
from PySide6.QtWidgets import QFormLayout
from superqt import QLabeledDoubleSlider
from superqt.utils import qthrottled

from leafstudio.core.bend import Pose
from leafstudio.forms.terms import RELIEF
from leafstudio.gui.model.bending import can_pose

THROTTLE_MS = 80  # as the parameter sliders (controls.py)
RANGES = {  # least, most, decimals
    "fold": (-75.0, 75.0, 1),
    "curl": (-1.0, 1.0, 2),
    "roll": (-20.0, 20.0, 1),
    "twist": (-3.1, 3.1, 2),
}
TIPS = {
    "fold": f"Fold: {RELIEF['fold']}. The sketch keeps the flat blade; the 3D leaf is bent.",
    "curl": "Curl: the midrib bends up on a circle of radius 1 / (2 curl) from the base, its "
    "length kept (a leaf of length 1 curled 0.5 lifts its apex 0.46 of its length; curled 1 "
    "turns the apex 115°; negative droops). The sketch keeps the flat blade.",
    "roll": "Roll: the blade rolls across its midrib into arcs of radius 1 / roll (in the leaf's "
    "lengths; negative rolls down), widths kept. The sketch keeps the flat blade.",
    "twist": "Twist: each cross-section turns about the midrib by twist · x radians from the "
    "base (a leaf of length 1 turns its apex by twist; 3.1 is half a turn). The sketch keeps "
    "the flat blade.",
}
SHEET_TIP = (
    "This scan is bent by the smooth sheet fitted to all its points; a fold or curl would "
    "replace that fit, so the sliders are off for it."
)


class BendSliders(QObject):
    """Three superqt sliders; `changed(pose, final)` on every move, final on release."""

    changed = Signal(object, bool)  # Pose, final

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.sliders: dict[str, QLabeledDoubleSlider] = {}
        for name, (low, high, decimals) in RANGES.items():
            slider = QLabeledDoubleSlider(Qt.Orientation.Horizontal)
            slider.setRange(low, high)
            slider.setDecimals(decimals)
            slider.setValue(0.0)
            slider.setToolTip(TIPS[name])
            slider.valueChanged.connect(self._moved)
            slider.sliderReleased.connect(self._released)
            self.sliders[name] = slider
        self._throttled = qthrottled(self._emit, timeout=THROTTLE_MS, leading=True)

    def pose(self) -> Pose:
        """The pose the sliders show."""
        return Pose(**{name: float(s.value()) for name, s in self.sliders.items()})

    def is_dragging(self) -> bool:
        return any(s.isSliderDown() for s in self.sliders.values())

    def show_pose(self, pose: Pose) -> None:
        """Show `pose` without emitting (undo, another document). A term beyond a slider's
        range (a form's grass blade rolled 188 times its length) widens that slider's range to
        hold it, so that moving another slider keeps it (clamped to 20, it was lost)."""
        for name, slider in self.sliders.items():
            value = getattr(pose, name)
            low, high = RANGES[name][:2]
            slider.blockSignals(True)
            slider.setRange(min(low, value), max(high, value))
            slider.setValue(value)
            slider.blockSignals(False)

    def set_enabled(self, on: bool, why_not: str = "") -> None:
        """Enable the sliders, or disable them with `why_not` as their tooltip."""
        for name, slider in self.sliders.items():
            slider.setEnabled(on)
            slider.setToolTip(TIPS[name] if on or not why_not else why_not)

    def _moved(self, *_: Any) -> None:
        if self.is_dragging():
            self._throttled()
        else:  # a key, a typed value, a click on the groove: one step at once
            self._throttled.cancel()
            self.changed.emit(self.pose(), True)

    def _emit(self) -> None:
        self.changed.emit(self.pose(), not self.is_dragging())

    def _released(self) -> None:
        self._throttled.cancel()
        self.changed.emit(self.pose(), True)


def install(window: Any) -> BendSliders:
    """Put the sliders in the window's Parameters panel under the Grid row, wired to its
    session both ways. Returns them."""
    bend = BendSliders(window)
    panel, session = window.panel, window.session
    form = panel.layout()
    assert isinstance(form, QFormLayout)
    row = form.getWidgetPosition(panel.widgets["grid"])[0] + 1
    for offset, (name, slider) in enumerate(bend.sliders.items()):
        form.insertRow(row + offset, name.capitalize(), slider)
        form.labelForField(slider).setToolTip(TIPS[name])
    bend.changed.connect(lambda pose, final: session.set_bend(pose, final))

    def shown(*_: Any) -> None:
        leaf = session.leaf
        bend.set_enabled(can_pose(leaf), SHEET_TIP if leaf is not None else "")
        if not bend.is_dragging():
            bend.show_pose(session.pose)

    session.state_changed.connect(shown)
    shown()
    return bend
