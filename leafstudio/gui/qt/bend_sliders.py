"""The Fold, Curl, Roll and Twist sliders in the Parameters panel, under K and the grid (issue 21,
build item 6): they bend the document's leaf live through `Session.set_bend`
(gui/model/bending.py), one undo step per drag; undo, a new document or an opened project
shows its pose on them.

Each reads as the Forms dock's term of the same name (forms/terms.RELIEF), over the same
range: fold is the angle each half turns up about the midrib, widths kept (about a straight
crease from base to apex: a midrib that bows sideways stands off it, README); curl bends the
midrib on a circle of radius 1 / (2 curl) from the base, its length kept (a leaf curled 0.5
lifts its apex 0.46 of its length, curled 1 turns it 115°); roll is the share of a half turn
the widest margins roll through, widths kept (1 closes the blade into a tube); twist is the
half turns the apex makes against the base. The pose they set is `core.bend.Pose`'s, per the
blade's length (gui/model/bending.py): roll a curvature, roll share · π over the blade's half
width (`half_width`), twist twist · π radians. The panel's roll was that curvature and its twist
in radians: the dock's grass blade rolled 1 showed a roll of 188, and its twist of 1 read 3.14.

Each slider's number is typed into, through the panel's own field (typed_field.TypedField) over
the term declared as a `paramspec.Real` (`TERMS`): a value past the slider's range is refused
with a note under the panel, not clamped (superqt's box bent a typed fold of 90 to 75 and -200
to -75 without a word).

Edit > Fit pose again (`FIT_ACTIONS`) asks the session to fit a pose to the document's curves in
3D once more (gui/model/pose_fits.py: on the worker, its fit one undo step, its refusal said in
a note); it is on while the leaf has no bend and its curves stand bent in 3D.
"""

from __future__ import annotations

from typing import Any

from PySide6.QtCore import QObject, Qt, Signal
from PySide6.QtWidgets import QFormLayout
from superqt import QLabeledDoubleSlider
from superqt.utils import qthrottled

from leafstudio.core.bend import Pose
from leafstudio.core.pose_limits import seam_note
from leafstudio.errors import LeafError
from leafstudio.forms.terms import RELIEF
from leafstudio.gui.model.bending import can_pose, pose_terms, sheet_tip, terms_pose
from leafstudio.gui.model.jobs import describe
from leafstudio.gui.qt.actions import Action
from leafstudio.gui.qt.typed_field import TypedField
from leafstudio.paramspec import Real

THROTTLE_MS = 80  # as the parameter sliders (controls.py)
RANGES = {  # least, most, decimals: the Forms dock's (forms/make.LIMITS)
    "fold": (-75.0, 75.0, 1),
    "curl": (-1.0, 1.0, 2),
    "roll": (-1.0, 1.0, 2),
    "twist": (-1.0, 1.0, 2),
}
TIPS = {
    name: f"{name.capitalize()}: {RELIEF[name]}. The sketch keeps the flat blade; the 3D leaf "
    "is bent."
    for name in RANGES
}
TERMS = {  # each slider's term as its typed field reads it (a Params field's declaration)
    name: Real(
        default=0.0,
        what=name,
        label=name.capitalize(),
        help=TIPS[name],
        stage="bend",  # no pipeline stage: the leaf's bend (gui/model/bending.py)
        flag=f"--{name}",  # `form`'s
        low=low,
        high=high,
        decimals=decimals,
    )
    for name, (low, high, decimals) in RANGES.items()
}


class BendSliders(QObject):
    """Four superqt sliders; `changed(pose, final)` on every move, final on release."""

    changed = Signal(object, bool)  # Pose, final
    refused = Signal(str)  # why a typed value was not taken; "" when one was

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.half_width = 1.0  # the blade's, per its length (bending.blade_half_width)
        self._shown = (Pose(), {})  # the pose show_pose showed, and the values it set
        self.sliders: dict[str, QLabeledDoubleSlider] = {}
        self.fields: dict[str, TypedField] = {}  # each slider's number, typed into
        for name, (low, high, decimals) in RANGES.items():
            slider = QLabeledDoubleSlider(Qt.Orientation.Horizontal)
            slider.setRange(low, high)
            slider.setDecimals(decimals)
            slider.setValue(0.0)
            slider.setToolTip(TIPS[name])
            slider.valueChanged.connect(self._moved)
            slider.sliderReleased.connect(self._released)
            self.sliders[name] = slider
            field = self.fields[name] = TypedField(slider, TERMS[name])
            field.refused.connect(self.refused)
        self._throttled = qthrottled(self._emit, timeout=THROTTLE_MS, leading=True)

    def pose(self) -> Pose:
        """The pose the sliders show (a term its slider still shows as `show_pose` set it keeps
        that pose's value to the bit, not its value through the units and back)."""
        terms = {name: float(slider.value()) for name, slider in self.sliders.items()}
        return terms_pose(terms, self.half_width, self._shown)

    def is_dragging(self) -> bool:
        return any(s.isSliderDown() for s in self.sliders.values())

    def show_pose(self, pose: Pose) -> None:
        """Show `pose` without emitting (undo, another document). A term beyond a slider's
        range (a leaf rolled past a tube, or a grass blade rolled 188 times its length shown
        at the sliders' own half width of 1) widens that slider's range to hold it, so that
        moving another slider keeps it (clamped, it was lost)."""
        values = {}
        for name, value in pose_terms(pose, self.half_width).items():
            slider = self.sliders[name]
            low, high = RANGES[name][:2]
            slider.blockSignals(True)
            slider.setRange(min(low, value), max(high, value))
            slider.setValue(value)
            slider.blockSignals(False)
            self.fields[name].show_value()  # its valueChanged was blocked: the field too
            values[name] = float(slider.value())
        self._shown = (pose, values)

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


def bend_leaf(window: Any, pose: Pose, final: bool, say: Any = None) -> bool:
    """The window's `session.set_bend`, the Parameters panel's sliders' and the Forms dock's:
    a pose past what it keeps of the blade (core/pose_limits.py) is refused with a message on
    release (not at every step of a drag) and the document kept as it was. False when refused.
    On release `say` (a note's setter) is told of a roll eased off a folded or twisted tube's
    seam (pose_limits.seam_note), "" when the roll was taken as asked."""
    session = window.session
    try:
        session.set_bend(pose, final)
    except LeafError as exc:
        if final:
            window.show_error("Bend", describe(exc))
        return False
    if final and say is not None:
        say(seam_note(pose_terms(pose, session.half_width)["roll"], pose.fold, pose.twist))
    return True


FIT_ACTIONS = (
    Action(
        "edit.fit_pose",
        "Edit",
        "&Fit pose again",
        lambda w: w.session.fit_pose_again(),
        tip="Fit the fold, curl, roll and twist that lay this leaf's 3D curves flat once more "
        "(a refused fit is otherwise kept through the leaf's edits)",
        separator=True,
    ),
)


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

    def bent(pose: Pose, final: bool) -> None:
        if not bend_leaf(window, pose, final, panel.say) and final:
            shown()  # the sliders back on the document's pose

    def shown(*_: Any) -> None:
        leaf = session.leaf
        scan_open = session.state.scan is not None
        bend.set_enabled(can_pose(leaf), sheet_tip(scan_open, True) if leaf is not None else "")
        window.actions["edit.fit_pose"].setEnabled(session.can_fit_pose())
        if not bend.is_dragging():
            if can_pose(leaf):  # a sheet-bent scan's sliders are off: no width to read
                bend.half_width = session.half_width
            bend.show_pose(session.pose)

    def fitting(text: str) -> None:  # Fit pose again under way (a run of 2-3 s for a cup)
        window.status_text.setStyleSheet("")
        window.status_text.setText(text)

    window.add_actions(FIT_ACTIONS)
    bend.changed.connect(bent)
    bend.refused.connect(panel.say)
    session.state_changed.connect(shown)
    session.fitting.connect(fitting)
    shown()
    return bend
