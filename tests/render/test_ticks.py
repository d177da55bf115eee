"""A colour bar's ticks (render/ticks.FittingTicks): apart, and 0 among them where it is on
the bar (the lesson's plans read their bars by it: g's edge, a height above the plane)."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from matplotlib.figure import Figure

from leafstudio.render.step_slides import _colour_bar


def _ticks(lo: float, hi: float, width: float) -> list[float]:
    """The ticks a plan's colour bar from `lo` to `hi` shows in a figure `width` pixels wide."""
    figure = Figure(figsize=(width / 96, 1.5), dpi=96, layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    axes.set_axis_off()
    _colour_bar(axes, ScalarMappable(Normalize(lo, hi), "viridis"), "g")
    figure.canvas.draw()
    bar = figure.axes[1]
    return [t for t in bar.get_xticks() if lo <= t <= hi]


@pytest.mark.parametrize(("lo", "hi", "width"), [(-0.27, 0.35, 60), (-0.021, 0.024, 60)])
def test_a_bar_with_room_for_one_tick_shows_its_zero(lo, hi, width):
    """review34: soybean pot1_1's lesson at 960 x 600 drew g's bar 53 pixels long under a
    bent leaf's plan, its one tick "−0.25": the edge, g = 0, not said; heights' bars alike
    ("−0.02")."""
    assert _ticks(lo, hi, width) == [0.0]


def test_a_short_bar_keeps_two_ticks_with_zero_where_they_fit():
    """review34: z(x)'s bar on that lesson, -0.012 to 0.031 over 83 pixels, said "0" alone,
    where every second nice number from 0 ("0.00", "0.02") fits apart."""
    ticks = _ticks(-0.012, 0.031, 160)
    assert len(ticks) >= 2 and 0.0 in np.round(ticks, 12)
