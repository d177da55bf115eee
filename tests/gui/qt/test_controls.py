"""The parameter panel: made from Params' declarations (a control, range, label and tooltip for
each), Auto K, valid values kept exactly, and the last value always emitted."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QLabel,
)
from superqt import QLabeledSlider, QLargeIntSpinBox

import leafstudio as ls
from leafstudio.gui.qt.controls import THROTTLE_MS, ParamPanel
from leafstudio.model import PARAMS, SEED_MAX, Params
from leafstudio.paramspec import Choice, Ranged, Switch, Whole
from tests.gui.builders import FAST

from .conftest import wait_result
from .stepping import STEPS, step


def test_every_control_and_its_label_explain_themselves(qtbot):
    panel = ParamPanel()
    qtbot.addWidget(panel)
    for name, param in PARAMS.items():
        widget = panel.widgets[name]
        assert widget.toolTip() == param.help_text() and len(widget.toolTip()) > 30
    assert len(panel.auto_k.toolTip()) > 30
    labels = [w for w in panel.findChildren(QLabel) if w.text() and w.toolTip()]
    assert {w.text() for w in labels} == {
        p.label for p in PARAMS.values() if not isinstance(p, Switch)
    }


def test_each_declared_parameter_has_its_control_over_its_declared_range(qtbot):
    """The panel offers what validation takes: a slider's ends sit inside the valid range and are
    both taken by Params; a choice offers exactly the declared words."""
    panel = ParamPanel()
    qtbot.addWidget(panel)
    assert list(panel.widgets) == list(PARAMS)  # every field has a control (margin had none)
    for name, param in PARAMS.items():
        widget = panel.widgets[name]
        if isinstance(param, Switch):
            assert isinstance(widget, QCheckBox) and widget.text() == param.label
        elif isinstance(param, Choice):
            assert isinstance(widget, QComboBox)
            assert [widget.itemText(i) for i in range(widget.count())] == list(param.choices)
        else:
            assert isinstance(param, Ranged)
            shown = (widget.minimum(), widget.maximum())
            assert shown == pytest.approx(param.panel_range)
            assert param.low <= shown[0] < shown[1] <= param.high
            assert isinstance(widget, QLabeledSlider if param.slider else QLargeIntSpinBox)
            for end in shown:  # both ends of the control are valid Params
                widget.setValue(end)
                assert getattr(panel.params(), name) == pytest.approx(end)
    assert panel.seed.maximum() == SEED_MAX  # the whole seed range (a QSpinBox stops at 2**31)


def test_a_loaded_projects_values_are_kept_exactly_even_outside_the_sliders(qtbot):
    """A slider widens to show a valid value outside its range; an edit of another control keeps
    every value the user did not touch (nothing clamped or rounded, margin included)."""
    panel = ParamPanel()
    qtbot.addWidget(panel)
    far = Params(
        k=40,
        grid=2048,
        mpu_tolerance=1.234567e-6,
        samples=100,
        seed=SEED_MAX,
        mesher="bpa",
        radius_factor=7.77777,
        taper=0.0123456,
        refine=False,
        margin="exact",
    )
    for name, param in PARAMS.items():
        if isinstance(param, Ranged) and param.slider is not None:
            assert not param.slider[0] <= getattr(far, name) <= param.slider[1]  # outside
    panel.set_params(far)
    assert panel.params() == far
    assert panel.grid.maximum() == 2048 and panel.k.maximum() == 40
    panel.mesher.setCurrentText("conforming")
    assert panel.params() == far.with_(mesher="conforming")
    panel.k.setValue(3)
    assert panel.params().k == 3
    panel.set_params(Params())  # the next document: the declared ranges again
    assert (panel.grid.minimum(), panel.grid.maximum()) == PARAMS["grid"].panel_range
    assert panel.params() == Params()


def test_a_moved_slider_gives_a_tidy_value(qtbot):
    panel = ParamPanel()
    qtbot.addWidget(panel)
    panel.taper.setValue(0.123456789)
    assert panel.params().taper == round(0.123456789, PARAMS["taper"].decimals + 2)
    assert panel.fields["taper"].text() == "0.12"  # the field follows the slider
    panel.grid.setValue(256)
    assert panel.fields["grid"].text() == "256"
    assert isinstance(PARAMS["k"], Whole) and PARAMS["k"].special == "auto"


def test_params_round_trip_through_the_controls(qtbot):
    panel = ParamPanel()
    qtbot.addWidget(panel)
    params = Params(
        k=7,
        grid=256,
        mpu_tolerance=0.002,
        samples=6000,
        seed=5,
        mesher="bpa",
        radius_factor=1.5,
        taper=0.5,
        refine=False,
    )
    panel.set_params(params)
    assert panel.params() == params
    assert panel.radius_factor.isEnabled()  # only ball pivoting uses it


def test_a_drag_emits_the_first_and_the_last_value(qtbot):
    panel = ParamPanel()
    qtbot.addWidget(panel)
    emitted = []
    panel.changed.connect(emitted.append)
    for value in range(16, 400, 8):
        panel.grid.setValue(value)
    qtbot.waitUntil(lambda: bool(emitted) and emitted[-1].grid == 392, timeout=5000)
    assert [p.grid for p in emitted] == [16, 392]  # throttled: at once, then the last


def test_auto_k(qtbot):
    panel = ParamPanel()
    qtbot.addWidget(panel)
    panel.auto_k.setChecked(True)
    assert panel.params().k == "auto" and not panel.k.isEnabled()
    panel.set_params(Params(k=5))
    assert not panel.auto_k.isChecked() and panel.params().k == 5
    panel.set_params(Params(k="auto"))
    assert panel.auto_k.isChecked() and panel.params() == Params(k="auto")


def test_a_project_keeps_its_parameters_through_a_panel_edit_in_the_window(window, qtbot, tmp_path):
    """Issue 12: the panel allowed K 1-12, grid 16-512, 500+ samples, a taper up to 1 and seeds up
    to 99999 where validation takes more, and had no margin control: a project's valid values
    were clamped, and its margin reset, at the first edit in the panel."""
    saved = FAST.with_(samples=120, taper=1.5, margin="exact", seed=2**31 + 5)
    path = tmp_path / "p.leaf.json"
    ls.save_leaf(ls.demo("nested"), path, saved)
    assert window.open_path(str(path))
    wait_result(qtbot, window, lambda o: o.result.params == saved)
    window.panel.k.setValue(4)
    outcome = wait_result(qtbot, window, lambda o: o.result.params.k == 4)
    assert outcome.result.params == saved.with_(k=4)
    assert window.session.params == saved.with_(k=4)


def type_into(qtbot, field, text: str) -> None:
    """Select the field's text, type `text` and press Return, as a user does."""
    field.setFocus()
    field.selectAll()
    qtbot.keyClicks(field, text)
    qtbot.keyClick(field, Qt.Key.Key_Return)


def test_a_typed_valid_value_past_the_slider_is_taken_and_widens_it(qtbot):
    """Before: superqt's number field clamped a typed K = 20 to the slider's 12 and a grid of
    1024 to 512, both valid (K up to 64, grid up to 2048)."""
    panel = ParamPanel()
    qtbot.addWidget(panel)
    panel.show()
    emitted = []
    panel.changed.connect(emitted.append)
    typed = (("k", "20", 20, "20"), ("grid", "1024", 1024, "1024"), ("taper", "2.5", 2.5, "2.50"))
    for name, text, value, shown in typed:
        param = PARAMS[name]
        assert param.slider[1] < value <= param.high  # past the slider, inside the valid range
        type_into(qtbot, panel.fields[name], text)
        assert getattr(panel.params(), name) == value
        assert panel.widgets[name].maximum() >= value  # the slider widened to show it
        assert panel.fields[name].text() == shown
        qtbot.waitUntil(lambda n=name, v=value: getattr(emitted[-1], n) == v, timeout=2000)
    assert panel.note.isHidden()
    type_into(qtbot, panel.fields["grid"], "200")  # inside the slider: simply taken
    assert panel.params().grid == 200 and panel.grid.value() == 200
    type_into(qtbot, panel.fields["k"], "auto")  # K's word, too
    assert panel.auto_k.isChecked() and panel.params().k == "auto"


@pytest.mark.parametrize(
    ("name", "text", "message"),
    [
        ("k", "65", "K must be between 1 and 64, got 65"),
        ("grid", "4096", "grid must be between 8 and 2048, got 4096"),
        ("grid", "abc", "grid must be a whole number, got 'abc'"),
        ("grid", "100.5", "grid must be a whole number"),
        ("taper", "9", "taper must be between 0.01 and 5, got 9"),
    ],
)
def test_a_typed_invalid_value_is_refused_with_params_message(qtbot, name, text, message):
    panel = ParamPanel()
    qtbot.addWidget(panel)
    panel.show()
    emitted = []
    panel.changed.connect(emitted.append)
    before = panel.params()
    shown = panel.fields[name].text()
    type_into(qtbot, panel.fields[name], text)
    assert panel.params() == before and not emitted  # nothing applied, nothing sent
    assert panel.fields[name].text() == shown  # the value in force is shown again
    assert panel.note.isVisible() and message in panel.note.text()
    assert f"{PARAMS[name].what} stays {shown}" in panel.note.text()
    if "between" not in message or name == "k":  # what it takes, unless the message says it
        assert PARAMS[name].describe() in panel.note.text()
    type_into(qtbot, panel.fields[name], shown)  # unchanged: nothing happens, the note stays
    type_into(qtbot, panel.fields["k"], "5")  # the next value taken clears the note
    assert panel.note.isHidden() and panel.params().k == 5
    type_into(qtbot, panel.fields[name], text)
    panel.set_params(Params(k=4))  # so does the next document (or an undo)
    assert panel.note.isHidden()


def test_a_projects_small_value_is_shown_and_kept_while_its_field_is_left_alone(qtbot):
    panel = ParamPanel()
    qtbot.addWidget(panel)
    panel.show()
    far = Params(mpu_tolerance=1.234567e-6, taper=0.0123456)
    panel.set_params(far)
    assert panel.fields["mpu_tolerance"].text() == "1.23e-06"
    field = panel.fields["taper"]
    field.setFocus()
    qtbot.keyClick(field, Qt.Key.Key_Return)  # finished without a change
    assert panel.params() == far  # not rounded to what the field shows


def test_a_typed_value_in_the_window_is_one_undo_step(window, qtbot):
    type_into(qtbot, window.panel.fields["k"], "14")
    outcome = wait_result(qtbot, window, lambda o: o.result.params.k == 14)
    assert outcome.result.params == FAST.with_(k=14)
    assert window.session.history.undo_text() == "Change K"
    window.session.undo()
    assert window.panel.params().k == FAST.k and window.panel.fields["k"].text() == str(FAST.k)
    assert window.panel.k.maximum() == PARAMS["k"].panel_range[1]  # back to the declared range


def test_leaving_a_field_or_the_seed_box_reads_what_was_typed(qtbot):
    panel = ParamPanel()
    qtbot.addWidget(panel)
    panel.show()
    panel.activateWindow()
    qtbot.waitActive(panel)

    def leave_after_typing(widget, text: str) -> None:
        widget.setFocus()
        qtbot.waitUntil(widget.hasFocus)
        (widget.lineEdit() if widget is panel.seed else widget).selectAll()
        qtbot.keyClicks(widget, text)
        panel.mesher.setFocus()
        qtbot.waitUntil(lambda: not widget.hasFocus())

    leave_after_typing(panel.seed, "-7")
    assert panel.params().seed == 0 and "got -7" in panel.note.text()
    leave_after_typing(panel.seed, "77")
    assert panel.params().seed == 77 and panel.note.isHidden()
    leave_after_typing(panel.fields["grid"], "777")
    assert panel.params().grid == 777 and panel.grid.maximum() == 777


SEED_STEPS_SCRIPT = """
import json, sys
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QApplication
app = QApplication([])
from leafstudio.gui.qt.controls import ParamPanel
from tests.gui.qt.stepping import STEPS, step
panel = ParamPanel()
panel.show()
box, seen = panel.seed, []
for text in sys.argv[1:]:
    for how in STEPS:
        box.setFocus()
        box.lineEdit().selectAll()
        QTest.keyClicks(box.lineEdit(), text)
        typed = box.lineEdit().text()
        step(QTest, box, how)  # QTest has qtbot's keyClick and mouseClick
        seen.append([text, how, typed, box.value(), panel.note.text()])
        panel.set_params(panel.params().with_(seed=0))
print(json.dumps(seen))
"""


def test_text_int_cannot_read_then_a_step_does_not_crash_the_seed_box(tmp_path):
    """Review s3 #1: superqt read the typed text with a bare int() in stepBy; `--5`, `½` or a lone
    `-` typed and then Up, Page Up, the wheel or an arrow raised inside Qt and killed the app
    (exit 139). Run in a child process, so that a crash fails this test, not the test run."""
    root = Path(__file__).resolve().parents[3]
    env = {**os.environ, "PYTHONPATH": str(root)}
    done = subprocess.run(
        [sys.executable, "-c", SEED_STEPS_SCRIPT, "--5", "½", "-"],
        cwd=root,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    seen = {(text, how): rest for text, how, *rest in json.loads(done.stdout)}
    assert len(seen) == 3 * len(STEPS)
    for how in STEPS:
        # the box takes no text int() cannot read: `--5` types as -5, `½` not at all
        typed, value, note = seen["--5", how]
        assert typed == "-5" and value == 0 and "got -5; seed stays 0" in note
        typed, value, note = seen["½", how]
        assert typed == "0" and value == (10 if how == "page up" else 1) and note == ""
        typed, value, note = seen["-", how]
        assert value == 0 and "seed must be a whole number, got '-'; seed stays 0" in note


@pytest.mark.parametrize("how", ("return", *STEPS))
def test_a_typed_seed_out_of_range_is_refused_not_clamped(qtbot, how):
    """Before: superqt's box clamped a typed seed of -5 to 0 and 10**23 to 2**32 - 1, quietly.
    Review s3 #1: after Return was fixed, `-5` then Up still stepped to 1 with no word, and 10**23
    then Up became 2**32 - 1; a step refuses it as Return does, and is not taken from it."""
    panel = ParamPanel()
    qtbot.addWidget(panel)
    panel.show()
    emitted = []
    panel.changed.connect(emitted.append)
    box = panel.seed
    for text in ("-5", "1" + "0" * 23):
        box.setFocus()
        box.lineEdit().selectAll()
        qtbot.keyClicks(box.lineEdit(), text)
        step(qtbot, box, how)
        assert box.value() == 0 and box.lineEdit().text() == "0"
        assert panel.note.isVisible() and "seed stays 0" in panel.note.text()
        assert f"seed must be between 0 and {SEED_MAX}, got {text[:5]}" in panel.note.text()
    assert panel.params().seed == 0 and not emitted
    box.lineEdit().selectAll()
    qtbot.keyClicks(box.lineEdit(), "41")  # a value taken is stepped from, exactly
    step(qtbot, box, how)
    expected = {"return": 41, "page up": 51}.get(how, 42)
    assert panel.params().seed == expected and panel.note.isHidden()
    qtbot.waitUntil(lambda: bool(emitted) and emitted[-1].seed == expected, timeout=2000)
    box.lineEdit().selectAll()
    qtbot.keyClicks(box.lineEdit(), str(SEED_MAX))  # the top seed is taken, not stepped past
    step(qtbot, box, how)
    assert panel.params().seed == SEED_MAX and panel.note.isHidden()
    qtbot.waitUntil(lambda: emitted[-1].seed == SEED_MAX, timeout=2000)


def test_text_typed_into_k_is_dropped_when_auto_k_comes_in_from_outside(qtbot):
    """Review s3 #5: K typed but not applied, then Auto K shown from outside (an undo, a project):
    the disabled field lost focus, read its stale text, unchecked Auto K and set K, two changes
    (two undo steps) that overrode the undo. The field now shows the slider's value again."""
    panel = ParamPanel()
    qtbot.addWidget(panel)
    panel.show()
    panel.activateWindow()
    qtbot.waitActive(panel)
    emitted = []
    panel.changed.connect(emitted.append)
    field = panel.fields["k"]
    field.setFocus()
    qtbot.waitUntil(field.hasFocus)
    field.selectAll()
    qtbot.keyClicks(field, "7")
    panel.set_params(Params(k="auto"))
    qtbot.waitUntil(lambda: not field.hasFocus())
    qtbot.wait(THROTTLE_MS * 3)  # a change would have been sent by now
    assert panel.auto_k.isChecked() and panel.params() == Params(k="auto") and not emitted
    assert field.text() == str(panel.k.value())


def test_an_undo_while_a_slider_is_held_leaves_its_drag_no_base_from_before(window, qtbot):
    """Review s3 finding 3, for a slider: Ctrl+Z while K's slider was held kept the drag's base
    (K 5), so letting go made a step from K 5 and undoing it brought back the undone change."""
    session, history, slider = window.session, window.session.history, window.panel.k
    session.set_params(session.params.with_(k=5))  # "Change K": 3 -> 5
    slider.setSliderDown(True)
    slider.setValue(6)
    qtbot.waitUntil(lambda: session.params.k == 6)
    window.actions["edit.undo"].trigger()
    undone = session.state
    assert undone.params.k == 3 and slider.value() == 3
    slider.setValue(4)
    qtbot.waitUntil(lambda: session.params.k == 4)
    slider.setSliderDown(False)  # let go: one step, from the state the undo made
    assert history.index == 1 and history.steps[0].before is undone
    window.actions["edit.undo"].trigger()
    assert session.state is undone
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)


def test_undo_to_auto_k_is_not_overridden_by_k_typed_and_not_applied(window, qtbot):
    """Review s3 #5 in the window: K typed, then Undo (menu or toolbar) back to Auto K gave K = 7
    (the typed text, read when the disabled field lost focus) instead of Auto K."""
    window.panel.auto_k.setChecked(True)
    wait_result(qtbot, window, lambda o: o.result.params.k == "auto")
    window.panel.auto_k.setChecked(False)
    wait_result(qtbot, window, lambda o: o.result.params.k == FAST.k)
    window.activateWindow()
    qtbot.waitActive(window)
    field = window.panel.fields["k"]
    field.setFocus()
    qtbot.waitUntil(field.hasFocus)
    field.selectAll()
    qtbot.keyClicks(field, "7")
    window.actions["edit.undo"].trigger()
    wait_result(qtbot, window, lambda o: o.result.params.k == "auto")
    qtbot.wait(THROTTLE_MS * 3)  # a change would have been sent by now
    assert window.session.params == FAST.with_(k="auto") and window.panel.auto_k.isChecked()
    assert window.worker.is_idle() and window.session.shown.outcome.result.params.k == "auto"
