"""A vein's heights along it, reshaped through a few handles (no Qt; gui/qt/profile_view.py
draws it).

t is the share of the vein's length from its base (0) to its tip (1). The profile starts from the
vein's own heights (its `line`, the heights before this edit) with handles lying on them, so
handles alone never change a height. Moving a handle by d moves the vein by a smooth bump that
is d under the handle and fades to nothing at its two neighbouring handles: a monotone cubic
(PCHIP, no overshoot) through the handles' displacements, zero at every untouched handle. A tiny
drag is therefore a tiny change, and nothing beyond the neighbouring handles moves. The first and
last handles stay at the ends. The boundary's heights (a loaded leaf's margin, from its relief)
are shown the same way, going once round it (`boundary_line`), without handles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import PchipInterpolator
from scipy.spatial import cKDTree

from leafstudio.core.prepare.vein_order import midrib_turned
from leafstudio.gui.model.curves import plane_arc_lengths
from leafstudio.gui.model.sketch_model import BOUNDARY, Sketch

PROFILE_HANDLES = 5  # handles of a profile made from a vein of this many points or more
MIN_GAP = 0.02  # the least share of the length between two neighbouring handles


@dataclass(frozen=True, eq=False)
class Profile:
    """Handles on a vein's heights.

    Parameters
    ----------
    t : (k,) float array
        Increasing shares of the vein's length, t[0] = 0 and t[-1] = 1 (k >= 2).
    h : (k,) float array
        The handles' heights.
    line_t, line_h : (n,) float arrays, optional
        The vein's heights along it before this edit (shares increasing from 0 to 1); by default
        the polyline through the handles. A handle whose height is the line's there is untouched.
    """

    t: np.ndarray
    h: np.ndarray
    line_t: np.ndarray | None = None
    line_h: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float).reshape(-1)
        h = np.asarray(self.h, dtype=float).reshape(-1)
        line_t = t if self.line_t is None else np.asarray(self.line_t, dtype=float).reshape(-1)
        line_h = h if self.line_h is None else np.asarray(self.line_h, dtype=float).reshape(-1)
        for name, value in (("t", t), ("h", h), ("line_t", line_t), ("line_h", line_h)):
            object.__setattr__(self, name, value)

    @classmethod
    def of_vein(
        cls,
        fractions: np.ndarray,
        heights: np.ndarray,
        line: tuple[np.ndarray, np.ndarray] | None = None,
        at: np.ndarray | None = None,
    ) -> Profile:
        """Handles on a vein whose control points lie at shares `fractions` of its length with
        heights `heights`; `line` is its heights along its curve (shares, heights; by default
        the polyline through the control points). The handles go at shares `at` (a profile's
        handles kept on a changed vein) or, by default, on up to PROFILE_HANDLES control points
        spread evenly along it (always its first and last; every point of a shorter vein)."""
        fractions = np.asarray(fractions, dtype=float)
        heights = np.asarray(heights, dtype=float)
        if len(fractions) < 2 or fractions[-1] <= fractions[0]:
            h = float(heights[0]) if len(heights) else 0.0
            return cls(np.array([0.0, 1.0]), np.array([h, h]))
        line_t, line_h = (fractions, heights) if line is None else line
        if at is None:
            targets = np.linspace(0.0, 1.0, min(PROFILE_HANDLES, len(fractions)))
            at = fractions[np.unique(np.abs(fractions[None, :] - targets[:, None]).argmin(axis=1))]
        t = np.unique(np.clip(np.asarray(at, dtype=float), 0.0, 1.0))
        t = np.concatenate([[0.0], t[(t > 0) & (t < 1)], [1.0]])
        return cls(t, np.interp(t, line_t, line_h), line_t, line_h)

    def rest(self, t: np.ndarray) -> np.ndarray:
        """The vein's heights before this edit at shares `t`."""
        return np.interp(np.clip(np.asarray(t, dtype=float), 0.0, 1.0), self.line_t, self.line_h)

    def offsets(self, t: np.ndarray) -> np.ndarray:
        """How far the handles have moved the vein at shares `t` (exactly 0 where no handle
        on either side has moved)."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, 1.0)
        moved = self.h - self.rest(self.t)
        if not np.any(moved):
            return np.zeros(np.shape(t))
        return PchipInterpolator(self.t, moved)(t)

    def heights(self, t: np.ndarray) -> np.ndarray:
        """Heights of the profile at shares `t` of the vein's length (held flat past 0 and 1)."""
        return self.rest(t) + self.offsets(t)

    def applied(self, fractions: np.ndarray, heights: np.ndarray) -> np.ndarray:
        """The vein's control heights after this edit, where `fractions` and `heights` are its
        control points' shares and heights before it."""
        return np.asarray(heights, dtype=float) + self.offsets(fractions)

    def moved(self, index: int, t: float, h: float) -> Profile:
        """The profile with handle `index` dragged to (t, h): an end handle moves up and down
        only, an inner one stays between its neighbours."""
        ts, hs = self.t.copy(), self.h.copy()
        low, high = ts[index - 1] + MIN_GAP, ts[min(index + 1, len(ts) - 1)] - MIN_GAP
        if 0 < index < len(ts) - 1 and low <= high:  # closer neighbours: it holds its place
            ts[index] = float(np.clip(t, low, high))
        hs[index] = float(h)
        return Profile(ts, hs, self.line_t, self.line_h)

    def with_handle(self, t: float) -> tuple[Profile, int] | None:
        """The profile with one more handle at share `t`, lying on the profile (so no height
        changes), and its index; None when `t` is not at least MIN_GAP from every handle."""
        if not (MIN_GAP <= t <= 1 - MIN_GAP) or np.min(np.abs(self.t - t)) < MIN_GAP:
            return None
        index = int(np.searchsorted(self.t, t))
        h = float(self.heights(np.array([t]))[0])
        ts, hs = np.insert(self.t, index, t), np.insert(self.h, index, h)
        return Profile(ts, hs, self.line_t, self.line_h), index

    def bridged(self, index: int) -> Profile:
        """The profile with inner handle `index` pulled onto the smooth curve through the other
        handles (PCHIP): what removing that handle does to the vein, between its neighbours."""
        others = np.delete(np.arange(len(self.t)), index)
        h = float(PchipInterpolator(self.t[others], self.h[others])(self.t[index]))
        return self.moved(index, float(self.t[index]), h)


def end_words(sketch: Sketch, vein: int) -> tuple[str, str]:
    """The words under the side view's left and right ends for `vein` of `sketch` (BOUNDARY:
    the boundary, from its point 1 round to it): the base and the tip, the other way round for a
    midrib written apex first, whose profile runs from its tip (vein_order.midrib_turned, as the
    length, the placement and the 3D view take it; 0.3 ms a paint)."""
    if vein == BOUNDARY:
        return "point 1", "round to point 1"
    turned = vein == 0 and midrib_turned(list(sketch.veins))
    return ("tip", "base") if turned else ("base", "tip")


def boundary_line(sketch: Sketch) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The boundary's heights going once round it from its first control point: the shares of
    its length (0 to 1, the loop closed) and heights along its curve, and the shares at its
    control points. Empty arrays below 3 control points. The heights are the sketch's own
    (`Sketch.boundary_heights`: from a loaded leaf's relief; 0 for a drawn leaf)."""
    curve = sketch.boundary_curve()
    if len(curve) < 3:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    loop = np.vstack([curve, curve[:1]])
    arc = plane_arc_lengths(loop)
    shares = arc / arc[-1]
    _, nearest = cKDTree(curve).query(sketch.boundary)  # each control point's own sample
    return shares, sketch.boundary_heights(loop), shares[nearest]
