"""The vein side view's handles without Qt (issue 12): a drag starts from the vein's own heights
and changes only what lies between the dragged handle's neighbours; handles are added on the
profile without changing it and removed by pulling the vein onto the curve through the rest."""

from __future__ import annotations

import numpy as np

from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.gui.model.vein_profile import MIN_GAP, PROFILE_HANDLES, Profile


def wiggly_vein(points: int = 11) -> Sketch:
    """A leaf whose one vein has heights that a curve through 5 handles cannot follow."""
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    boundary = np.column_stack([0.5 + 0.45 * np.cos(t), 0.2 * np.sin(t)])
    x = np.linspace(0.05, 0.95, points)
    vein = np.column_stack([x, 0.05 * np.sin(3 * x), 0.04 + 0.02 * np.sin(17 * x)])
    return Sketch(boundary=boundary, veins=(vein,))


def vein_profile(sketch: Sketch) -> tuple[Profile, np.ndarray, np.ndarray]:
    shares, heights = sketch.vein_fractions(0), sketch.veins[0][:, 2]
    return Profile.of_vein(shares, heights), shares, heights


def test_a_tiny_drag_on_a_long_vein_is_a_tiny_change_everywhere():
    """The finding: on a vein of more than 5 points the first drag smoothed the heights between
    the handles (points far from the handle moved by ~0.02 for a drag of 1e-4)."""
    profile, shares, heights = vein_profile(wiggly_vein(11))
    assert len(profile.t) == PROFILE_HANDLES < len(shares)
    dragged = profile.moved(2, profile.t[2], profile.h[2] + 1e-4)
    change = dragged.heights(shares) - heights
    assert np.abs(change).max() <= 1e-4 + 1e-12
    assert np.isclose(change.max(), 1e-4)  # the point under the handle moved by the drag


def test_a_grab_without_a_move_changes_no_height():
    profile, shares, heights = vein_profile(wiggly_vein(11))
    for index in range(len(profile.t)):
        same = profile.moved(index, profile.t[index], profile.h[index])
        np.testing.assert_array_equal(same.applied(shares, heights), heights)


def test_a_drag_moves_only_the_points_between_the_handles_neighbours_without_overshoot():
    profile, shares, heights = vein_profile(wiggly_vein(21))
    k, rise = 2, 0.03
    after = profile.moved(k, profile.t[k], profile.h[k] + rise).applied(shares, heights)
    change = after - heights
    outside = (shares <= profile.t[k - 1]) | (shares >= profile.t[k + 1])
    np.testing.assert_array_equal(after[outside], heights[outside])
    inside = ~outside
    assert inside.sum() >= 3 and np.all(change[inside] > 0) and np.all(change <= rise + 1e-12)
    under = int(np.argmin(np.abs(shares - profile.t[k])))
    assert np.isclose(change[under], rise)
    # the bump rises to the handle and falls after it: the vein's own wiggles are kept on top
    assert np.all(np.diff(change[inside & (shares <= profile.t[k])]) >= -1e-15)
    assert np.all(np.diff(change[inside & (shares >= profile.t[k])]) <= 1e-15)


def test_a_handle_dragged_sideways_holds_the_vein_at_its_new_place_between_its_neighbours():
    profile, shares, heights = vein_profile(wiggly_vein(21))
    moved = profile.moved(2, profile.t[2] + 0.1, profile.h[2])
    assert np.isclose(moved.t[2], profile.t[2] + 0.1)
    assert np.isclose(moved.heights(np.array([moved.t[2]]))[0], profile.h[2])
    far = shares >= moved.t[3]
    np.testing.assert_array_equal(moved.applied(shares, heights)[far], heights[far])


def test_adding_a_handle_changes_no_height_and_keeps_its_distance():
    profile, shares, heights = vein_profile(wiggly_vein(11))
    dense = np.linspace(0, 1, 301)
    added = profile.with_handle(0.37)
    assert added is not None
    more, index = added
    assert more.t[index] == 0.37 and len(more.t) == len(profile.t) + 1
    np.testing.assert_array_equal(more.heights(dense), profile.heights(dense))
    np.testing.assert_array_equal(more.applied(shares, heights), heights)
    assert profile.with_handle(profile.t[1] + MIN_GAP / 2) is None  # on top of a handle
    assert profile.with_handle(0.0) is None and profile.with_handle(1.0) is None
    # a drag of the new handle reaches only as far as its neighbours, the old handles
    after = more.moved(index, 0.37, more.h[index] + 0.02).applied(shares, heights)
    outside = (shares <= more.t[index - 1]) | (shares >= more.t[index + 1])
    np.testing.assert_array_equal(after[outside], heights[outside])


def test_removing_a_handle_pulls_the_vein_onto_the_curve_through_the_others():
    profile, shares, heights = vein_profile(wiggly_vein(11))
    k = 2
    raised = profile.moved(k, profile.t[k], profile.h[k] + 0.05).applied(shares, heights)
    # the view rebuilds the handles on the new heights (same places)
    kept = Profile.of_vein(shares, raised, at=profile.t)
    np.testing.assert_array_equal(kept.t, profile.t)
    assert np.isclose(kept.h[k], profile.h[k] + 0.05)
    flattened = kept.bridged(k).applied(shares, raised)
    under = int(np.argmin(np.abs(shares - profile.t[k])))
    others = np.delete(np.arange(len(kept.t)), k)
    through = np.interp(profile.t[k], kept.t[others], kept.h[others])  # roughly, the others' line
    assert abs(flattened[under] - through) < 0.01 < abs(raised[under] - through)
    outside = (shares <= kept.t[k - 1]) | (shares >= kept.t[k + 1])
    np.testing.assert_array_equal(flattened[outside], raised[outside])


def test_removing_a_handle_just_added_to_an_even_slope_changes_nothing():
    profile, shares, _ = vein_profile(wiggly_vein(11))
    slope = 0.02 + 0.03 * shares
    even = Profile.of_vein(shares, slope, at=profile.t)
    more, index = even.with_handle(0.6)
    after = more.bridged(index).applied(shares, slope)
    np.testing.assert_allclose(after, slope, rtol=0, atol=1e-15)


def test_removing_a_handle_just_added_to_a_wiggly_vein_smooths_only_between_its_neighbours():
    profile, shares, heights = vein_profile(wiggly_vein(21))
    more, index = profile.with_handle(0.6)
    after = more.bridged(index).applied(shares, heights)
    outside = (shares <= more.t[index - 1]) | (shares >= more.t[index + 1])
    np.testing.assert_array_equal(after[outside], heights[outside])
    assert not np.array_equal(after, heights)


def test_kept_handles_sit_on_the_veins_own_curve():
    sketch = wiggly_vein(4)
    curve = sketch.vein_curve(0)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(curve[:, :2], axis=0), axis=1))])
    line = (arc / arc[-1], curve[:, 2])
    profile = Profile.of_vein(sketch.vein_fractions(0), sketch.veins[0][:, 2], line, [0.0, 0.45, 1])
    np.testing.assert_array_equal(profile.t, [0.0, 0.45, 1.0])
    assert np.isclose(profile.h[1], np.interp(0.45, *line))
    np.testing.assert_allclose(profile.h[[0, -1]], sketch.veins[0][[0, -1], 2])


def curled(sketch: Sketch) -> Sketch:
    """`sketch` with a relief that tilts its boundary: height 0.1 (x - 0.5), as a loaded leaf's
    margin keeps its heights."""
    from dataclasses import replace

    outline = sketch.boundary_curve()
    return replace(sketch, relief=np.column_stack([outline, 0.1 * (outline[:, 0] - 0.5)]))


def test_the_boundarys_heights_go_once_round_it_from_its_first_point():
    from leafstudio.gui.model.vein_profile import boundary_line

    sketch = curled(wiggly_vein(5))
    shares, heights, points = boundary_line(sketch)
    assert shares[0] == 0 and shares[-1] == 1 and np.all(np.diff(shares) > 0)
    assert heights[0] == heights[-1]  # the loop is closed
    loop = np.vstack([sketch.boundary_curve(), sketch.boundary_curve()[:1]])
    np.testing.assert_allclose(heights, 0.1 * (loop[:, 0] - 0.5), atol=2e-3)
    assert len(points) == len(sketch.boundary) and points[0] == 0 and np.all(np.diff(points) > 0)
    np.testing.assert_allclose(
        np.interp(points, shares, heights), 0.1 * (sketch.boundary[:, 0] - 0.5), atol=2e-3
    )
    flat = boundary_line(wiggly_vein(5))[1]  # a drawn leaf: on the plane
    assert len(flat) and not flat.any()
    assert all(len(a) == 0 for a in boundary_line(Sketch(boundary=sketch.boundary[:2])))
