"""Colour-bar ticks that never touch (FittingTicks), for the lesson's plan pictures at any size
(render/step_slides.py). Imports matplotlib: imported only where a picture is drawn."""

from __future__ import annotations

import numpy as np
from matplotlib.font_manager import FontProperties
from matplotlib.textpath import text_to_path
from matplotlib.ticker import MaxNLocator

# the least room between two labels, in their ems: g's "−0.1", "0.0" and "0.1", 0.8 em apart
# at the lesson's smallest plan, read apart (its 0 kept: where the edge is)
TICK_GAP = 0.5
MOST_TICKS = 6  # where the bar's length holds them (a slide's bars, 9 inches: 4 to 6)
STEPS = (1, 2, 2.5, 5, 10)  # the nice numbers ticks fall on, as MaxNLocator's default


class FittingTicks(MaxNLocator):
    """A horizontal colour bar's ticks on nice numbers, as many as its length holds when it is
    drawn with their labels TICK_GAP apart: on the lesson's plan at its smallest window
    (960 x 600), z(x)'s bar 140 pixels long said "0.010.020.03" in one run.

    Parameters
    ----------
    size_pt : float
        The tick labels' font size, in points (as the bar's tick_params set it).
    """

    def __init__(self, size_pt: float) -> None:
        super().__init__(nbins=MOST_TICKS, steps=list(STEPS))
        self.size_pt = size_pt

    def __call__(self) -> np.ndarray:
        """The ticks at the bar's length as laid out now (matplotlib asks at each draw): the
        most nice ticks whose labels are apart, from runs of nice numbers and every second or
        third of them (nice numbers on the nested demo's z(x), 0 to 0.037, are 0.01 apart at
        least for two ticks on the bar: 39 pixels on a 143-pixel bar, where "0.01" is 45
        wide), 0 among them where it is on the bar, else one tick: 0 where it is on the bar.

        0 is kept because the plans' bars read by it: g's edge, a height above the plane. On
        a scan's lesson at 960 x 600, g's bar (-0.27 to 0.35, 53 pixels) said "−0.25" alone,
        and z(x)'s (-0.012 to 0.031, 83 pixels) "0" alone where "0.00 0.02" fit (review34)."""
        lo, hi = sorted(self.axis.get_view_interval())
        length = self.axis.axes.bbox.width  # pixels
        slack = 1e-9 * (hi - lo)
        runs = []
        for bins in range(MOST_TICKS, 0, -1):
            self.set_params(nbins=bins)
            ticks = self.tick_values(lo, hi)
            ticks = ticks[(ticks >= lo - slack) & (ticks <= hi + slack)]  # on the bar
            zero = np.flatnonzero(np.abs(ticks) <= slack)
            start = int(zero[0]) if len(zero) else 0
            runs.append(ticks)
            for stride in (2, 3):  # from the first, and from 0 (kept)
                runs += [ticks[::stride], ticks[start % stride :: stride]]
        fitting = [t for t in runs if len(t) >= 2 and self._apart(t, lo, hi, length)]
        if fitting:  # the most ticks, 0 among them if any has it (max: the first of equals)
            return max(fitting, key=lambda t: (len(t), bool(np.any(np.abs(t) <= slack))))
        if lo - slack <= 0 <= hi + slack:
            return np.zeros(1)
        coarsest = runs[-5]
        return coarsest[len(coarsest) // 2 :][:1]  # its middle

    def _apart(self, ticks: np.ndarray, lo: float, hi: float, length: float) -> bool:
        """Whether the (n,) ticks' labels, centred on them along `length` pixels from `lo` to
        `hi`, leave TICK_GAP between each two."""
        font, pixels = FontProperties(size=self.size_pt), self.axis.get_figure().dpi / 72
        labels = self.axis.major.formatter.format_ticks(list(ticks))
        widths = pixels * np.array(
            [text_to_path.get_text_width_height_descent(t, font, "$" in t)[0] for t in labels]
        )
        at = (ticks - lo) / ((hi - lo) or 1.0) * length
        room = np.diff(at) - (widths[:-1] + widths[1:]) / 2
        return bool(np.all(room >= TICK_GAP * self.size_pt * pixels))
