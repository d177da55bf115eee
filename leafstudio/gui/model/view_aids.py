"""The view aids' decisions, without Qt (gui/qt/explain.py draws them): K as the view's corner
says it, and whether the view may stretch a result's relief (appreview31, findings 4 and 8);
when the layer laying a bent leaf flat follows the layers drawn there (`BladeFollow`: the window
ticks it, main_window.py).
"""

from __future__ import annotations

from typing import Any

from leafstudio.core.evaluate import NO_MIXTURE

FLAT_K = f"K {NO_MIXTURE}"
# said where the stretch is set (Height ×, the lesson) while it is off for a posed leaf
STRETCH_OFF = (
    "Height × is off for a bent leaf: a stretch along one axis would stretch its bend (a fold, "
    "a curl, a scan's curve), not its relief."
)


def k_label(result: Any) -> str:
    """K as the view's corner shows it: the K the surface uses (`Result.chosen_k`), or that
    none is fitted. A blade with no relief of its own (no veins, or all in its plane) fits no
    mixture: its gmm stage is one Gaussian of amplitude 0 (core/steps.compute_gmm), whose
    chosen_k of 1 the view said beside a K slider at 3 (appreview31, finding 8)."""
    k = result.fitted_k
    return FLAT_K if k is None else f"K = {k}"


def stretches(result: Any) -> bool:
    """Whether the view may stretch `result` along its flat blade's normal (explain.
    stretch_matrix) to exaggerate its relief: only an unbent leaf's. A leaf posed by a form's or
    the sliders' fold, curl, roll or twist carries its bend along that axis: ovate curled 1,
    stretched 3 times (Height × 3, the lesson), drew its midrib 2.37 long instead of 0.99, its
    extent along the normal 0.765 to 2.295 for a relief of 0.078 (appreview31, finding 4). A
    scan's sheet is no better: its flat blade's normal is 5-36° off the scan's own plane and
    the curled blade stands 20-26 mm along it (soybean pot1_1 and pot1_15, sugar beet pot2_1,
    37-48 mm long), which three times over is no relief."""
    return getattr(result.leaf, "bend", None) is None


# the layers a bent leaf's run draws on its flat blade (fields.py: g, its zero contour, p(x),
# the EM samples), where the "blade" layer lays its outline and input points (layers.py)
FLAT_LAYERS = ("contour", "implicit", "probability", "em")


class BladeFollow:
    """Whether the "Bent leaf laid flat" layer follows the layers drawn on the flat blade: a
    bent leaf's g, p(x) and EM samples were drawn on its flat blade, away from the bent mesh
    and its points, with the layer that lays the leaf flat under them left off (closing32).
    Ticked with the first of them on a bent leaf, unticked with the last off, or when the leaf
    is no longer bent, if it ticked the layer itself; a tick the user gives or takes off is
    the user's (taken off while they show, it stays off until they are all off)."""

    def __init__(self) -> None:
        self.auto = False  # the blade layer is on because this ticked it
        self.declined = False  # the user took it off while a flat layer showed

    def ticked(self, ticks: dict[str, bool], bent: bool, changed: str | None = None) -> bool | None:
        """The blade layer's tick for the layers' `ticks` on a leaf that is `bent` or not,
        after layer `changed` was (un)ticked (None: a new result): True or False to set it,
        None to leave it as it is."""
        flat_on = any(ticks.get(key, False) for key in FLAT_LAYERS)
        blade = ticks.get("blade", False)
        if changed == "blade":  # the user's own
            self.auto, self.declined = False, not blade and flat_on
            return None
        if not flat_on:
            self.declined = False
        if self.auto and blade and not (flat_on and bent):
            self.auto = False
            return False
        if flat_on and bent and not blade and not self.declined:
            self.auto = True
            return True
        return None
