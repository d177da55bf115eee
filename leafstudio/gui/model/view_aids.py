"""The view aids' decisions, without Qt (gui/qt/explain.py draws them): K as the view's corner
says it, and whether the view may stretch a result's relief (appreview31, findings 4 and 8).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from leafstudio.core.bend import Pose
from leafstudio.core.placed import PlacedPose

FLAT_K = "K unused (flat blade)"
# said where the stretch is set (Height ×, the lesson) while it is off for a posed leaf
STRETCH_OFF = (
    "Height × is off for a bent leaf: a stretch along one axis would stretch its fold or curl, "
    "not its relief."
)


def k_label(result: Any) -> str:
    """K as the view's corner shows it: the K the surface uses (`Result.chosen_k`), or that
    none is fitted. A blade with no relief of its own (no veins, or all in its plane) fits no
    mixture: its gmm stage is one Gaussian of amplitude 0 (core/steps.compute_gmm), whose
    chosen_k of 1 the view said beside a K slider at 3 (appreview31, finding 8)."""
    if not np.any(result.em_mixture.amplitudes):
        return FLAT_K
    return f"K = {result.chosen_k}"


def stretches(result: Any) -> bool:
    """Whether the view may stretch `result` along its flat blade's normal (explain.
    stretch_matrix) to exaggerate its relief: not a leaf posed by a form's or the sliders'
    fold, curl, roll or twist (a Pose or PlacedPose), whose bend that axis carries. Ovate curled
    1, stretched 3 times (Height × 3, the lesson), drew its midrib 2.37 long instead of 0.99,
    its extent along the normal 0.765 to 2.295 for a relief of 0.078 (appreview31, finding 4).
    A scan's sheet stays stretched: its gentle curve is the relief the view shows."""
    return not isinstance(getattr(result.leaf, "bend", None), (Pose, PlacedPose))
