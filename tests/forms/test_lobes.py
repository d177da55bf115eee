"""Lobed margins have rounded lobes and U-shaped sinuses, as in an oak (issue 22, finding 6:
"5 lobes" on an ovate leaf was a zig-zag like a lightning bolt)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from leafstudio.forms import make_form

BROAD = ["elliptic", "oblong", "ovate", "obovate", "orbicular", "deltoid", "spatulate"]
STEP = 0.015  # of the length: the margin's turn is measured over this much either side


def sharpest_turn(boundary: np.ndarray, lo: float = 0.08, hi: float = 0.85) -> float:
    """The margin's sharpest turn (degrees) between its directions STEP before and after a
    point, over the points with lo < x < hi (the lobed part: not the base or the apex)."""
    ring = shapely.LinearRing(boundary[:, :2])
    at = np.arange(0.0, ring.length, 0.002)

    def along(arc: np.ndarray) -> np.ndarray:
        return shapely.get_coordinates(shapely.line_interpolate_point(ring, arc % ring.length))

    point, before, after = along(at), along(at - STEP), along(at + STEP)
    a, b = point - before, after - point
    cos = (a * b).sum(axis=1) / np.linalg.norm(a, axis=1) / np.linalg.norm(b, axis=1)
    turn = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    return float(turn[(point[:, 0] > lo) & (point[:, 0] < hi)].max())


@pytest.mark.parametrize("shape", BROAD)
@pytest.mark.parametrize("lobes", [5, 7])
def test_pinnate_lobes_are_rounded_not_a_zig_zag(shape, lobes):
    leaf = make_form(shape, margin="lobed", lobes=lobes)
    assert sharpest_turn(leaf.boundary) < 100.0  # V-shaped sinuses turned 107-143 degrees


@pytest.mark.parametrize("shape", BROAD)
def test_sinuses_reach_a_quarter_of_the_way_to_the_midvein(shape):
    """The term's definition (forms.terms: lobed), Ellis et al.'s (Manual of Leaf Architecture,
    2009): sinuses cut at least a quarter of the way to the midvein. The glossary said "deeper
    than a tenth of the width", which a class would apply to shallowly sinuate leaves."""
    from leafstudio.forms.terms import MARGINS

    assert "a quarter of the way to the midvein" in MARGINS["lobed"]
    lobed = make_form(shape, margin="lobed", lobes=5).boundary[:, :2]
    entire = make_form(shape).boundary[:, :2]
    x = np.linspace(0.15, 0.8, 200)

    def half_width(b: np.ndarray) -> np.ndarray:
        upper = b[b[:, 1] > 0]
        upper = upper[np.argsort(upper[:, 0])]
        return np.interp(x, upper[:, 0], upper[:, 1])

    cut = half_width(entire) - half_width(lobed)
    assert (cut / half_width(entire)).max() > 0.25
