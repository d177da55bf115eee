"""A whole vein's heights as one smooth profile along it (no Qt; gui/profile_view.py draws it).

The profile is a few handles (t, height), t being the share of the vein's length from its base
(0) to its tip (1); a monotone cubic (PCHIP: no overshoot between handles) through them gives a
height at every t, and each control point of the vein takes the height at its own t. Dragging a
handle therefore reshapes the whole vein at once; the first and last handles stay at the ends.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import PchipInterpolator

PROFILE_HANDLES = 5  # handles of a profile made from a vein of this many points or more
MIN_GAP = 0.02  # the least share of the length between two neighbouring handles


@dataclass(frozen=True, eq=False)
class Profile:
    """Handles of a height profile along a vein.

    Parameters
    ----------
    t : (k,) float array
        Increasing shares of the vein's length, t[0] = 0 and t[-1] = 1 (k >= 2).
    h : (k,) float array
        The heights at those places.
    """

    t: np.ndarray
    h: np.ndarray

    def __post_init__(self) -> None:
        object.__setattr__(self, "t", np.asarray(self.t, dtype=float).reshape(-1))
        object.__setattr__(self, "h", np.asarray(self.h, dtype=float).reshape(-1))

    @classmethod
    def of_vein(cls, fractions: np.ndarray, heights: np.ndarray) -> Profile:
        """The profile through up to PROFILE_HANDLES of a vein's control points, spread evenly
        along it (always its first and last): where `fractions` are the control points' shares
        of the vein's length and `heights` their heights. A vein of PROFILE_HANDLES points or
        fewer gets a handle on each point, so its profile passes through every height."""
        fractions = np.asarray(fractions, dtype=float)
        heights = np.asarray(heights, dtype=float)
        if len(fractions) < 2 or fractions[-1] <= fractions[0]:
            h = float(heights[0]) if len(heights) else 0.0
            return cls(np.array([0.0, 1.0]), np.array([h, h]))
        targets = np.linspace(0.0, 1.0, min(PROFILE_HANDLES, len(fractions)))
        chosen = np.unique(np.abs(fractions[None, :] - targets[:, None]).argmin(axis=1))
        t = fractions[chosen].copy()
        t[0], t[-1] = 0.0, 1.0
        keep = np.concatenate([[True], np.diff(t) > 0])
        return cls(t[keep], heights[chosen][keep])

    def heights(self, t: np.ndarray) -> np.ndarray:
        """Heights of the profile at shares `t` of the vein's length (held flat past 0 and 1)."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, 1.0)
        return PchipInterpolator(self.t, self.h)(t)

    def moved(self, index: int, t: float, h: float) -> Profile:
        """The profile with handle `index` dragged to (t, h): an end handle moves up and down
        only, an inner one stays between its neighbours."""
        ts, hs = self.t.copy(), self.h.copy()
        low, high = ts[index - 1] + MIN_GAP, ts[min(index + 1, len(ts) - 1)] - MIN_GAP
        if 0 < index < len(ts) - 1 and low <= high:  # closer neighbours: it holds its place
            ts[index] = float(np.clip(t, low, high))
        hs[index] = float(h)
        return Profile(ts, hs)

    def fits(self, fractions: np.ndarray, heights: np.ndarray, tolerance: float) -> bool:
        """True when this profile gives a vein's heights (at shares `fractions`) within
        `tolerance`: the vein is still the one it shaped."""
        if len(fractions) == 0:
            return False
        return bool(np.all(np.abs(self.heights(fractions) - heights) <= tolerance))
