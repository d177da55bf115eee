"""The sketch model without Qt: splines through the clicks, insertion, files."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import shapely

import leafstudio as ls
from leafstudio.core.evaluate import point_to_mesh_distance
from leafstudio.core.plane import Frame
from leafstudio.gui.model.curves import closed_curve, insert_index, open_curve
from leafstudio.gui.model.sketch_model import BOUNDARY, Sketch
from tests.leaves import clicked_sketch

SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


def test_the_closed_curve_passes_through_its_control_points_and_closes_smoothly():
    curve = closed_curve(SQUARE)
    for point in SQUARE:
        assert np.linalg.norm(curve - point, axis=1).min() < 1e-9
    steps = np.diff(np.vstack([curve, curve[:1]]), axis=0)
    turn = np.arccos(
        np.clip(
            (steps[:-1] * steps[1:]).sum(1)
            / np.linalg.norm(steps[:-1], axis=1)
            / np.linalg.norm(steps[1:], axis=1),
            -1,
            1,
        )
    )
    assert turn.max() < np.deg2rad(15)  # no corner anywhere, the seam included


def test_the_open_curve_runs_from_first_to_last_control_point():
    control = np.array([[0.0, 0.0, 0.1], [0.5, 0.2, 0.2], [1.0, 0.0, 0.1]])
    curve = open_curve(control)
    np.testing.assert_allclose(curve[0], control[0], atol=1e-12)
    np.testing.assert_allclose(curve[-1], control[-1], atol=1e-12)
    assert np.linalg.norm(curve - control[1], axis=1).min() < 1e-9


def test_a_new_point_goes_into_the_nearest_span_or_past_the_nearest_end():
    assert insert_index(SQUARE, np.array([0.5, -0.1]), closed=True) == 1
    assert insert_index(SQUARE, np.array([-0.1, 0.5]), closed=True) == 4
    line = np.array([[0.0, 0.0], [1.0, 0.0]])
    assert insert_index(line, np.array([-0.5, 0.0]), closed=False) == 0
    assert insert_index(line, np.array([1.5, 0.1]), closed=False) == 2
    assert insert_index(line, np.array([0.5, 0.1]), closed=False) == 1


def test_the_leaf_lies_on_the_sketch_plane_with_vein_heights_along_its_normal():
    frame = Frame(
        origin=np.array([1.0, 2.0, 3.0]),
        u=np.array([0.0, 1.0, 0.0]),
        v=np.array([0.0, 0.0, 1.0]),
        normal=np.array([1.0, 0.0, 0.0]),
    )
    sketch = Sketch(
        boundary=SQUARE, veins=(np.array([[0.2, 0.5, 0.3], [0.8, 0.5, 0.3]]),), frame=frame
    )
    leaf = sketch.to_leaf()
    np.testing.assert_allclose(leaf.boundary[:, 0], 1.0)
    np.testing.assert_allclose(leaf.veins[0][:, 0], 1.3)
    assert Sketch(boundary=SQUARE[:2]).to_leaf() is None


def test_edits_return_new_sketches_and_leave_the_old_one_alone():
    sketch = Sketch(boundary=SQUARE)
    moved = sketch.moved(BOUNDARY, 0, np.array([-1.0, -1.0]))
    assert sketch.boundary[0, 0] == 0.0 and moved.boundary[0, 0] == -1.0
    with_vein = sketch.with_vein(np.array([[0.5, 0.5, 0.1]]))
    assert sketch.veins == () and with_vein.veins[0].tolist() == [[0.5, 0.5, 0.1]]
    assert with_vein.default_height(0, np.array([0.6, 0.5])) == 0.1
    assert len(with_vein.deleted(BOUNDARY, 1).boundary) == 3
    assert with_vein.deleted(0, 0).veins == ()  # a vein without points goes


def test_a_sketch_survives_its_dict():
    sketch = Sketch(boundary=SQUARE, veins=(np.array([[0.2, 0.5, 0.3]]),))
    again = Sketch.from_dict(sketch.to_dict())
    np.testing.assert_array_equal(again.boundary, sketch.boundary)
    np.testing.assert_array_equal(again.veins[0], sketch.veins[0])
    np.testing.assert_array_equal(again.frame.normal, sketch.frame.normal)


def test_a_curled_boundary_keeps_its_heights_through_edits_and_files():
    """A loaded (scanned) leaf's margin lies off the plane: the sketch's boundary curve takes its
    heights from the loaded boundary (the relief), also after a point moves, and in a file."""
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    xy = np.column_stack([np.cos(t), 0.5 * np.sin(t)])
    height = 0.2 * xy[:, 1] ** 2 - 0.1 * xy[:, 0]  # a margin curled up at the sides
    sketch = Sketch(boundary=xy[::10], relief=np.column_stack([xy, height]))
    leaf = sketch.to_leaf()
    expected = 0.2 * leaf.boundary[:, 1] ** 2 - 0.1 * leaf.boundary[:, 0]
    assert np.abs(leaf.boundary[:, 2] - expected).max() < 0.01
    assert np.ptp(leaf.boundary[:, 2]) > 0.2
    moved = sketch.moved(BOUNDARY, 0, np.array([0.9, 0.0]))
    near = np.argmin(np.linalg.norm(moved.to_leaf().boundary[:, :2] - [0.9, 0.0], axis=1))
    assert abs(moved.to_leaf().boundary[near, 2] - (-0.1)) < 0.02  # the margin's height there
    again = Sketch.from_dict(moved.to_dict())
    np.testing.assert_allclose(again.to_leaf().boundary, moved.to_leaf().boundary)
    assert np.all(Sketch(boundary=xy[::10]).to_leaf().boundary[:, 2] == 0)  # drawn: on the plane


@pytest.mark.parametrize(
    ("shape", "terms"),
    [("ovate", {"margin": "serrate", "teeth": 30}), ("hastate", {"margin": "lobed", "lobes": 5})],
)
def test_a_loaded_toothed_leaf_keeps_its_teeth_when_one_point_is_moved(shape, terms):
    """Review finding: a loaded leaf became a sketch of 24 evenly spread points, so moving one
    boundary point wiped every tooth and the edit failed ("vein 1: 2 of 113 points lie outside
    the boundary"). The derived boundary now follows the outline within its tolerance."""
    from leafstudio.forms import make_form
    from leafstudio.gui.model.curves import OUTLINE_TOLERANCE

    result = ls.reconstruct(make_form(shape, **terms), ls.Params(grid=64))
    sketch = Sketch.from_result(result)
    curve = shapely.LinearRing(closed_curve(sketch.boundary))
    extent = np.ptp(result.polygon, axis=0).max()
    gap = shapely.distance(shapely.points(result.polygon), curve)
    assert gap.max() <= 2 * OUTLINE_TOLERANCE * extent
    edited = sketch.moved(BOUNDARY, 0, sketch.boundary[0] + 0.001 * extent)
    again = ls.reconstruct(edited.to_leaf(), ls.Params(grid=64))
    area = result.metrics["leaf"]["projected_area"]
    assert again.metrics["leaf"]["projected_area"] == pytest.approx(area, rel=0.01)


@pytest.mark.parametrize("repeat", [False, True])
def test_the_span_distance_check_bounds_the_distance_to_the_whole_curve(repeat):
    """outline_controls checks each outline point against its own span of the spline (20 ms of
    shapely on the main thread when a big file opened): never nearer than the whole curve,
    and equal to it where the spline follows the outline; a repeated control point (no span
    per pair) is measured against the whole curve."""
    from leafstudio.gui.model.curves import _span_distances

    t = np.linspace(0, 2 * np.pi, 3000, endpoint=False)
    r = 1 + 0.1 * np.sin(23 * t)
    polygon = np.column_stack([r * np.cos(t), 0.6 * r * np.sin(t)])
    chosen = np.arange(0, 3000, 40)
    control = polygon[chosen]
    if repeat:
        control = np.insert(control, 5, control[5], axis=0)
        chosen = np.insert(chosen, 5, chosen[5])
    curve = closed_curve(control)
    whole = shapely.distance(shapely.points(polygon), shapely.LinearRing(curve))
    spans = _span_distances(polygon, chosen, curve)
    assert np.all(spans >= whole - 1e-12)
    near = spans < 0.5 * np.median(spans[spans > 0])  # points the spline follows closely
    np.testing.assert_allclose(spans[near], whole[near], atol=1e-12)
    assert np.all(spans[chosen] <= 1e-12)  # the spline passes through its control points


def test_a_scans_hole_shows_on_the_sketch_of_its_flat_blade(tmp_path):
    """Issue 21: a scan's real hole was cut from the mesh only after bending, so the sketch of
    the flat blade showed none. It now holds the hole's ring where the flat blade has no scan
    point, inside the outline; a drawn leaf has none."""
    from leafstudio import workflows
    from tests.sources.test_scan_holes import RADIUS, _scan

    opened = workflows.open_scan(_scan(tmp_path, hole=True))
    result = workflows.reconstruct(opened, ls.Params(grid=64)).result
    sketch = Sketch.from_result(result)
    (ring,) = sketch.hole_curves()
    hole = shapely.Polygon(ring)
    assert shapely.Polygon(sketch.boundary_curve()).contains(hole)
    true = np.pi * (40.0 * RADIUS) ** 2  # its ring runs through the points around the hole
    assert 0.8 * true <= hole.area <= 2.0 * true  # (1.6 times the empty disc's area)
    blade = opened.scan[opened.extraction.blade]
    flat = sketch.frame.to_plane(opened.leaf.bend.flatten(blade))[0]
    inside = shapely.contains_xy(hole.buffer(-0.1 * 40.0 * RADIUS), flat[:, 0], flat[:, 1])
    assert not inside.any()  # where the scan has no point
    assert Sketch(boundary=ring[:-1]).hole_curves() == []


@pytest.mark.parametrize("shape", ["ovate", "obovate", "elliptic", "reniform"])
def test_the_sketch_shows_every_form_base_left_apex_right(shape):
    """An obovate, elliptic or spatulate form's sketch (and the 3D view, which takes the
    sketch's frame) showed the apex on the left and the base on the right, an ovate one the
    other way round, and a reniform one turned a quarter: the frame's u runs to the boundary's
    farther extreme, not along the midrib. The sketch now turns its frame a quarter or half
    turn so that the midrib runs from left to right, along u."""
    result = ls.reconstruct(ls.forms.make_form(shape), ls.Params(grid=48))
    sketch = Sketch.from_result(result)
    midrib = sketch.vein_curve(0)
    chord = midrib[-1, :2] - midrib[0, :2]
    assert chord[0] > 0.9 * np.linalg.norm(chord)  # base on the left, apex on the right
    np.testing.assert_allclose(sketch.frame.normal, result.frame.normal)
    drawn = shapely.Polygon(result.frame.to_plane(sketch.to_leaf().boundary)[0])
    outline = shapely.Polygon(result.polygon)
    assert drawn.symmetric_difference(outline).area < 0.02 * outline.area  # the same place


def test_a_leaf_at_1e_90_gets_a_sketch_of_its_outline():
    """The app's sketch of a leaf at 1e-90 (which `reconstruct` takes) failed with "zero-size
    array to reduction operation minimum": its curves dropped control points within an absolute
    1e-12 of the next as repeats, which was every one; repeats are now within 1e-12 of their
    extent."""
    leaf = ls.demo("nested")
    tiny = ls.Leaf(leaf.boundary * 1e-90, [v * 1e-90 for v in leaf.veins])
    sketch = Sketch.from_result(ls.reconstruct(tiny, ls.Params(grid=32)))
    assert len(sketch.boundary) >= 12
    curve = closed_curve(sketch.boundary[:, :2])
    assert len(curve) > len(sketch.boundary) and np.ptp(curve[:, 0]) > 0.5e-90


def test_curves_through_points_at_1e300_are_finite():
    """The app's sketch of a leaf at 1e300 failed with "`x` must contain only finite values":
    the centripetal parameter's chord lengths overflowed (their squares)."""
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    control = 1e300 * np.column_stack([np.cos(t), 0.4 * np.sin(t)])
    for curve in (closed_curve(control), open_curve(control[:6])):
        assert np.isfinite(curve).all() and np.ptp(curve[:, 0]) > 1e299


def test_a_vein_clicked_out_to_the_margin_lies_on_the_leaf():
    """The app's drawn leaf (tests/leaves.clicked_sketch: 12 outline points, a midrib and four
    side veins clicked out to near the margin, at the heights the editor gives new points):
    every point took the first one's height, 5% of the size, so the side veins' ends stood
    that high beside the margin, where the surface comes down to it, and hung in the air
    (0.019 of the length off the mesh). New points stood no higher over the margin than a
    form's veins, a quarter of their distance inside it; now the veins follow the dome over the
    outline (sketch_dome.py): every vein point on the surface."""
    sketch = clicked_sketch()
    heights = np.concatenate([v[:, 2] for v in sketch.veins])
    assert heights.max() > 0.04 * sketch.extent()  # the middle keeps a relief (the dome's)
    ends = np.array([v[-1] for v in sketch.veins[1:]])
    assert np.all(ends[:, 2] < 0.3 * heights.max())  # the side veins come down to the margin
    leaf = sketch.to_leaf()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = ls.reconstruct(leaf, ls.Params(k=3, grid=128))
    off = point_to_mesh_distance(result.triangle_mesh, leaf.vein_points) / result.length
    assert off.max() <= 1e-3


def test_a_new_vein_points_default_height_comes_down_to_a_drawn_margin_only():
    """The margin's rule (Sketch.default_height) on a drawn leaf: a point near the outline (the
    curve through the unit square's corners bulges 0.19 past them) stands at most a quarter of
    its distance inside, either sign, and nothing outside; a vein's later points keep
    their own height; a leaf whose margin has heights of its own (a relief), or a sketch with
    no outline, keeps the nearest point's height wherever (the review: a rolled leaf's midrib
    dipped 7% of its length where clicks between its points were pulled to the margin's)."""
    square = Sketch(boundary=SQUARE)
    edge = np.array([-0.15, 0.5])  # 0.04 inside the outline
    cap = 0.25 * shapely.LinearRing(square.boundary_curve()).distance(shapely.Point(edge))
    assert 0 < cap < 0.04 and square.default_height(-1, edge) == pytest.approx(cap)
    below = square.with_vein(np.array([[0.5, 0.5, -0.04], [0.6, 0.5, -0.04]]))
    assert below.default_height(0, edge) == pytest.approx(-cap)
    assert below.default_height(0, np.array([0.55, 0.5])) == -0.04  # its own, inside
    outside = np.array([1.25, 0.5])
    assert square.default_height(-1, outside) == 0.0
    relief = Sketch(
        boundary=SQUARE, veins=below.veins, relief=np.array([[0.0, 0.0, 0.2], [1.0, 1.0, 0.2]])
    )
    assert relief.default_height(0, edge) == -0.04
    no_outline = Sketch(veins=(np.array([[0.2, 0.0, 0.2], [0.5, 0.0, 0.2]]),))
    assert no_outline.default_height(0, np.array([0.6, 0.0])) == 0.2
