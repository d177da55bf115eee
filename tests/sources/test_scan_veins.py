"""A scan's veins lie on its own blade and run as veins do (issue 21): soybean pot1_1's midrib
crossed a bay of its unrolled blade (17.6% of its length outside it) and snaked, because on
that blade (core/sheet.py) its base was put by the points the outline cuts off there, taken for
a petiole: in a bay; the midribs of the other scans stepped where a lobe starts beside them (sugar
beet pot2_3: 84 degrees between tenths of its length); straight side veins off a bending
midrib crossed each other (soybean pot1_17: 5 pairs)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from scipy.spatial import cKDTree

from leafstudio.core.bend import flat_leaf
from leafstudio.core.plane import fit_frame
from tests.leaves import extracted_scan
from tests.photos import REALLEAVES

SCANS = sorted(REALLEAVES.glob("*.txt"))
pytestmark = pytest.mark.skipif(not SCANS, reason=f"no real scans at {REALLEAVES}")


def _turns(line: shapely.LineString, pieces: int = 10) -> tuple[float, float]:
    """The line's length over its ends' distance, and the largest turn (degrees) between its
    tenths: a midrib's bend, not the middles' wobble."""
    at = shapely.line_interpolate_point(line, np.linspace(0, 1, pieces + 1), normalized=True)
    points = shapely.get_coordinates(at)
    step = np.diff(points, axis=0)
    heading = np.arctan2(step[:, 1], step[:, 0])
    turn = np.degrees(np.abs(np.angle(np.exp(1j * np.diff(heading))))).max()
    return line.length / float(np.linalg.norm(points[-1] - points[0])), float(turn)


@pytest.mark.parametrize("scan", SCANS, ids=lambda p: p.stem)
def test_a_scans_veins_lie_on_its_blade_and_the_midrib_runs_straight_on(scan):
    points, found = extracted_scan(scan)
    flat = flat_leaf(found.leaf)
    frame = fit_frame(flat.boundary, np.zeros((0, 3)))
    blade = shapely.Polygon(frame.to_plane(flat.boundary)[0])
    lines = [shapely.LineString(frame.to_plane(v)[0]) for v in flat.veins]
    midrib = lines[0]
    assert len(lines) >= 5  # a midrib and side veins
    for line in lines:  # flat: inside the blade they are drawn on
        assert line.difference(blade).length <= 0.01 * midrib.length
    ratio, turn = _turns(midrib)
    assert ratio <= 1.15 and turn <= 45.0  # pot1_1 was 1.52 and 111 degrees
    for k, line in enumerate(lines[1:], start=1):  # side veins leave the midrib, cross nothing
        assert not shapely.LineString(shapely.get_coordinates(line)[1:]).intersects(midrib)
        assert not any(line.intersects(other) for other in lines[k + 1 :])
    # bent: on the scan, half of each vein within 2% of the length of a blade point (a vein
    # may cross a hole torn in the blade: sugar beet pot1_7's side vein, 3.3% at its 90th
    # percentile)
    near = cKDTree(points[found.blade])
    for vein in found.leaf.veins:
        assert np.median(near.query(vein)[0]) <= 0.02 * found.length


def test_a_side_vein_stops_at_the_midrib_it_would_cross():
    """A straight side vein on the inside of a strongly bending midrib (a half-ring blade) ran
    across the midrib itself: side veins stopped at other side veins, not at the midrib (a
    helper's outline setting made one on soybean pot1_1)."""
    from shapely.geometry import Polygon

    from leafstudio.sources.scan_veins import side_veins

    turn = np.linspace(np.pi, 0, 200)
    ring = [r * np.column_stack([np.cos(turn), np.sin(turn)]) for r in (1.4, 1.0, 0.6)]
    blade = Polygon(np.vstack([ring[0], ring[2][::-1]]))
    veins = side_veins(blade, ring[1], lambda p: np.ones(len(p), dtype=bool), 0.01)
    midrib = shapely.LineString(ring[1])
    assert len(veins) >= 8
    assert not any(shapely.LineString(v).intersects(midrib) for v in veins)


def test_a_midrib_reaches_a_tip_past_a_bay_on_the_blade():
    """A blade whose tip lies on a thin strip past a bay (sugar beet pot1_7's on its sheet at
    SMOOTHING 1e-3, core/sheet.py): the middles were taken on the bay's dead end, nearest the
    middle before, and smoothed they cut the bay's corner, 7% of the midrib's length (4.5 of its
    61 units) off the blade."""
    from leafstudio.sources.scan_outline import resample
    from leafstudio.sources.scan_veins import midline

    body = shapely.box(0.0, -0.2, 0.8, 0.1)
    lobe, strip = shapely.box(0.79, -0.2, 0.85, -0.1), shapely.box(0.79, 0.04, 1.0, 0.1)
    blade = shapely.geometry.polygon.orient(shapely.union_all([body, lobe, strip]))
    outline = resample(blade, 400)
    spacing = blade.length / 200
    midrib = shapely.LineString(midline(outline, np.array([0.0, -0.05]), spacing))
    assert midrib.difference(blade).length == 0.0
    assert midrib.distance(shapely.Point(1.0, 0.07)) <= 0.05  # it still reaches the tip


def test_the_way_through_leaves_a_bays_dead_end_and_keeps_all_parts_where_none_goes_through():
    """scan_veins.through: of a station's chord parts, those on a way from the base's station to
    the tip's (a part in a bay's dead end is dropped), and every part where no way goes through
    (nothing to choose by: the middles are then taken nearest the middle before)."""
    from leafstudio.sources.scan_veins import through

    one, two, dead_end = np.array([[-1.0, 1.0]]), np.array([[0.2, 1.0]]), np.array([-1.0, -0.2])
    ways = through([(0.0, one), (1.0, np.vstack([dead_end, two[0]])), (2.0, np.array([[0.3, 1]]))])
    assert np.array_equal(ways[1], two)
    assert np.array_equal(ways[0], one)

    apart = [(0.0, np.array([[-1.0, -0.4]])), (1.0, np.array([[0.5, 1.0], [1.2, 1.5]])),
             (2.0, np.array([[0.6, 1.0]]))]  # fmt: skip
    for (_, parts), kept in zip(apart, through(apart), strict=True):
        assert np.array_equal(kept, parts)


def test_a_smoothed_middle_off_its_part_is_put_back_inset_and_one_on_it_stays():
    """scan_veins.put_back: a middle smoothed off its chord part (MIDRIB_SMOOTH cuts a step's
    corner) goes back `inset` in from the nearer end, or to the middle of a part narrower than
    twice that; a middle on its part is left where it is."""
    from leafstudio.sources.scan_veins import put_back

    parts = np.array([[0.0, 1.0], [0.0, 1.0], [0.0, 1.0], [2.0, 2.3], [2.0, 2.3]])
    middles = np.array([-0.5, 1.7, 0.99, 2.6, 2.05])
    assert np.allclose(put_back(middles, parts, 0.2), [0.2, 0.8, 0.99, 2.15, 2.05])
