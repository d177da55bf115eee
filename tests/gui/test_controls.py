"""The parameter panel: a tooltip on every control, Auto K, and the last value always emitted."""

from __future__ import annotations

from PySide6.QtWidgets import QLabel

from leafstudio.gui.controls import TIPS, ParamPanel, auto_k_supported
from leafstudio.model import Params


def test_every_control_and_its_label_explain_themselves(qtbot):
    panel = ParamPanel()
    qtbot.addWidget(panel)
    for key in TIPS:
        widget = getattr(panel, "auto_k" if key == "auto" else key)
        assert len(widget.toolTip()) > 30
    labels = [w for w in panel.findChildren(QLabel) if w.text() and w.toolTip()]
    assert len(labels) >= 8


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


def test_auto_k_when_the_pipeline_offers_it(qtbot):
    panel = ParamPanel()
    qtbot.addWidget(panel)
    if not auto_k_supported():
        assert panel.auto_k.parent() is None
        return
    panel.auto_k.setChecked(True)
    assert panel.params().k == "auto" and not panel.k.isEnabled()
