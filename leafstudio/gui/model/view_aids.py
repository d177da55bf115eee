"""The view aids' decisions, without Qt (gui/qt/explain.py draws them): K as the view's corner
says it, and whether the view may stretch a result's relief (appreview31, findings 4 and 8).
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
