"""The parameter panel: one labelled control per Params field, each with a plain-words tooltip.

Every change emits `changed(Params)`, throttled so that a slider drag does not flood the worker:
the first value goes out at once and the last value always follows. `released` marks the end of
a slider drag (one undo step per drag: `is_dragging()` is True until then).
"""

from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QFormLayout,
    QSpinBox,
    QWidget,
)
from superqt import QLabeledDoubleSlider, QLabeledSlider
from superqt.utils import qthrottled

from leafstudio.errors import LeafError
from leafstudio.model import MESHERS, Params

THROTTLE_MS = 80
K_RANGE = (1, 12)
GRID_RANGE = (16, 512)

TIPS = {
    "k": "How many Gaussian bumps (the paper's K) make up the leaf's surface. One bump per main "
    "vein region is a good start; more bumps follow the veins more closely.",
    "auto": "Let LeafStudio choose K from 1 to 12 by the Bayesian information criterion.",
    "grid": "How finely the leaf is sampled: grid points along the leaf's length. Higher is "
    "smoother and slower (the time grows with the square of this number).",
    "mpu_tolerance": "How closely the leaf's outline function must follow the boundary points, as "
    "a fraction of the leaf's length. Smaller follows every wiggle; larger smooths noise.",
    "samples": "How many random points, drawn where the height guide is high, the Gaussian "
    "mixture is fitted to. More points give a steadier fit.",
    "seed": "The random seed for drawing those points. The same seed always gives the same leaf.",
    "mesher": "How the surface becomes triangles: 'conforming' follows the outline exactly; "
    "'bpa' is the ball pivoting of the paper, which may leave gaps at thin tips.",
    "radius_factor": "Ball pivoting only: scales the ball radii. Larger balls close gaps but can "
    "bridge notches in the outline.",
    "taper": "How wide the band along the margin is where the surface bends down to the "
    "outline, as a fraction of the leaf's inner radius.",
    "refine": "After the EM fit, adjust all bumps together so the surface passes closer to the "
    "veins (the paper stops after EM).",
}


def auto_k_supported() -> bool:
    """True once Params accepts k='auto' (automatic K, added by the analysis work)."""
    try:
        Params(k="auto")  # type: ignore[arg-type]
    except (LeafError, TypeError, ValueError):
        return False
    return True


class ParamPanel(QWidget):
    """Labelled sliders, spin boxes and choices for Params; `params()` reads them all."""

    changed = Signal(object)  # Params
    released = Signal()  # a slider was let go

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        form = QFormLayout(self)
        form.setFieldGrowthPolicy(QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)

        self.k = QLabeledSlider(Qt.Orientation.Horizontal)
        self.k.setRange(*K_RANGE)
        self.auto_k = QCheckBox("Auto")
        self.grid = QLabeledSlider(Qt.Orientation.Horizontal)
        self.grid.setRange(*GRID_RANGE)
        self.grid.setSingleStep(16)
        self.grid.setPageStep(64)
        self.mpu_tolerance = QLabeledDoubleSlider(Qt.Orientation.Horizontal)
        self.mpu_tolerance.setRange(0.0001, 0.02)
        self.mpu_tolerance.setDecimals(4)
        self.samples = QLabeledSlider(Qt.Orientation.Horizontal)
        self.samples.setRange(500, 20000)
        self.samples.setSingleStep(500)
        self.samples.setPageStep(2000)
        self.seed = QSpinBox()
        self.seed.setRange(0, 99999)
        self.mesher = QComboBox()
        self.mesher.addItems(MESHERS)
        self.radius_factor = QLabeledDoubleSlider(Qt.Orientation.Horizontal)
        self.radius_factor.setRange(0.5, 4.0)
        self.radius_factor.setDecimals(2)
        self.taper = QLabeledDoubleSlider(Qt.Orientation.Horizontal)
        self.taper.setRange(0.05, 1.0)
        self.taper.setDecimals(2)
        self.refine = QCheckBox("Refine after EM")

        rows = [
            ("K (Gaussians)", self.k, "k"),
            ("", self.auto_k, "auto"),
            ("Grid", self.grid, "grid"),
            ("MPU tolerance", self.mpu_tolerance, "mpu_tolerance"),
            ("EM samples", self.samples, "samples"),
            ("Seed", self.seed, "seed"),
            ("Mesher", self.mesher, "mesher"),
            ("Ball radius ×", self.radius_factor, "radius_factor"),
            ("Margin taper", self.taper, "taper"),
            ("", self.refine, "refine"),
        ]
        for label, widget, key in rows:
            widget.setToolTip(TIPS[key])
            if key == "auto" and not auto_k_supported():
                continue
            form.addRow(label, widget)
            if label:
                form.labelForField(widget).setToolTip(TIPS[key])

        self._emit_throttled = qthrottled(self._emit, timeout=THROTTLE_MS, leading=True)
        for slider in (
            self.k,
            self.grid,
            self.mpu_tolerance,
            self.samples,
            self.radius_factor,
            self.taper,
        ):
            slider.valueChanged.connect(self._on_edit)
            slider.sliderReleased.connect(self.released)
        self.seed.valueChanged.connect(self._on_edit)
        self.mesher.currentTextChanged.connect(self._on_edit)
        self.auto_k.toggled.connect(self._on_edit)
        self.refine.toggled.connect(self._on_edit)
        self.set_params(Params())

    def is_dragging(self) -> bool:
        """True while a slider is held down."""
        sliders = (self.k, self.grid, self.mpu_tolerance, self.samples, self.radius_factor)
        return any(s.isSliderDown() for s in (*sliders, self.taper))

    def params(self) -> Params:
        """The Params the controls show."""
        return Params(
            k="auto" if self.auto_k.isChecked() else int(self.k.value()),  # type: ignore[arg-type]
            grid=int(self.grid.value()),
            mpu_tolerance=round(float(self.mpu_tolerance.value()), 6),
            samples=int(self.samples.value()),
            seed=int(self.seed.value()),
            mesher=self.mesher.currentText(),
            radius_factor=round(float(self.radius_factor.value()), 4),
            taper=round(float(self.taper.value()), 4),
            refine=self.refine.isChecked(),
        )

    def set_params(self, params: Params) -> None:
        """Show `params` without emitting `changed` (values outside a slider's range are clamped
        by it; those params are what `params()` returns afterwards)."""
        widgets = (
            self.k,
            self.auto_k,
            self.grid,
            self.mpu_tolerance,
            self.samples,
            self.seed,
            self.mesher,
            self.radius_factor,
            self.taper,
            self.refine,
        )
        blocked = [w.blockSignals(True) for w in widgets]
        try:
            auto = params.k == "auto"
            self.auto_k.setChecked(auto)
            if not auto:
                self.k.setValue(int(params.k))
            self.grid.setValue(params.grid)
            self.mpu_tolerance.setValue(params.mpu_tolerance)
            self.samples.setValue(params.samples)
            self.seed.setValue(params.seed)
            self.mesher.setCurrentText(params.mesher)
            self.radius_factor.setValue(params.radius_factor)
            self.taper.setValue(params.taper)
            self.refine.setChecked(params.refine)
        finally:
            for widget, was in zip(widgets, blocked, strict=True):
                widget.blockSignals(was)
        self._sync_enabled()

    def _sync_enabled(self) -> None:
        self.k.setEnabled(not self.auto_k.isChecked())
        self.radius_factor.setEnabled(self.mesher.currentText() == "bpa")

    def _on_edit(self, *_: object) -> None:
        self._sync_enabled()
        self._emit_throttled()

    def _emit(self) -> None:
        self.changed.emit(self.params())
