"""Which of a mesh's points are the outline's (Result.on_outline), the margin whose normals and
curvatures are the surface's limits from inside: a bent leaf's cuts add points on it and a
scan's trim drops some (the exports and the view took the first len(polygon): sugar beet
pot1_7's trimmed mesh had 7 points up to 0.63 mm inside flagged, 2 on the outline not)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

import leafstudio as ls
from leafstudio.assets.asset import outline_distance
from leafstudio.forms import Form

ON_OUTLINE = 1e-9  # of the outline's extent: a point this near it lies on it (round-off: the
# cuts' points on the outline's edges are 1e-16 of it off; the nearest other point 2e-3)


def notched_blade() -> tuple[ls.Leaf, shapely.Polygon]:
    """An ellipse rolled on a scan's sheet, a hole torn into its margin and one inside
    (sheet_bend.Scaled.trim cuts both out of the bent mesh), and its flat blade less both."""
    from leafstudio.core.sheet import fit_sheet
    from leafstudio.core.sheet_bend import Scaled
    from tests.core.test_sheet import _blade, rolled

    sheet = fit_sheet(rolled(_blade(3000), 0.3), np.array([0.0, 0.0, 1.0]), 1.0)
    turn = np.linspace(0, 2 * np.pi, 33)
    notch = [0.1, 0.2] + 0.06 * np.column_stack([np.cos(turn), np.sin(turn)])
    hole = [-0.2, 0.0] + 0.05 * np.column_stack([np.cos(turn), np.sin(turn)])
    bend = Scaled(sheet, np.zeros(3), 1.0, holes=(notch, hole))
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    outline = np.column_stack([0.45 * np.cos(t), 0.18 * np.sin(t), np.zeros_like(t)])
    x = np.linspace(-0.4, 0.4, 30)
    midrib = np.column_stack([x, np.zeros_like(x), np.full_like(x, 0.01)])
    leaf = ls.Leaf(boundary=bend.bent(outline), veins=[bend.bent(midrib)], bend=bend)
    blade = shapely.Polygon(outline[:, :2]) - shapely.Polygon(notch) - shapely.Polygon(hole)
    return leaf, blade


def notched_leaf() -> ls.Leaf:
    """notched_blade's leaf."""
    return notched_blade()[0]


def on_the_outline(result: ls.Result) -> np.ndarray:
    """(n,) bool: the mesh's points within ON_OUTLINE of the outline, on the flat blade."""
    distance = outline_distance(result.polygon, result.mesh_on_blade()[0])
    return distance <= ON_OUTLINE * float(np.ptp(result.polygon, axis=0).max())


@pytest.fixture(scope="module")
def notched() -> ls.Result:
    return ls.reconstruct(notched_leaf(), ls.Params(k=2, grid=64))


def test_a_trimmed_meshs_outline_points_are_those_on_its_outline(notched):
    flagged, on = notched.on_outline(), on_the_outline(notched)
    first = np.arange(len(on)) < len(notched.polygon)
    assert (first != on).any()  # the trim renumbered them: the first len(polygon) are not it
    np.testing.assert_array_equal(flagged, on)
    assert np.array_equal(notched.unit.on_outline(), flagged)


@pytest.mark.parametrize("pose", [{"fold": 60.0}, {"fold": 75.0, "roll": 1.0}], ids=str)
def test_a_posed_meshs_outline_points_are_those_on_its_outline(pose):
    """A pose's crease cuts and sag halvings add points: those on the outline's edges are the
    outline's (they were not), those on a chord across the apex are not."""
    result = ls.reconstruct(Form("ovate", **pose).leaf(), ls.Params(k=3, grid=48))
    np.testing.assert_array_equal(result.on_outline(), on_the_outline(result))
