"""A whole vein's heights at once (issue 12), without Qt: the profile model and the session's
one undo step per drag."""

from __future__ import annotations

import numpy as np

from leafstudio.forms import make_form
from leafstudio.gui.model.session import Session
from leafstudio.gui.model.sketch_model import BOUNDARY, Sketch
from leafstudio.gui.model.vein_profile import MIN_GAP, PROFILE_HANDLES, Profile, end_words
from leafstudio.sources.demos import demo
from tests.leaves import sketch_clicks as ellipse


def leaf_with_vein(points: int) -> Sketch:
    x = np.linspace(0.05, 0.95, points)
    vein = np.column_stack([x, 0.05 * np.sin(3 * x), 0.04 + 0.02 * np.sin(5 * x)])
    return Sketch(boundary=ellipse(), veins=(vein,))


# --- the model (no Qt) -------------------------------------------------------------------------
def test_a_veins_shares_of_its_length_run_from_0_to_1_along_its_curve():
    sketch = leaf_with_vein(6)
    shares = sketch.vein_fractions(0)
    assert shares[0] == 0.0 and shares[-1] == 1.0 and np.all(np.diff(shares) > 0)
    np.testing.assert_allclose(shares, np.linspace(0, 1, 6), atol=0.02)  # evenly spaced points
    np.testing.assert_array_equal(Sketch(veins=([[0.1, 0.1, 0.0]],)).vein_fractions(0), [0.0])


def test_a_short_veins_profile_passes_through_every_height():
    sketch = leaf_with_vein(4)
    shares, heights = sketch.vein_fractions(0), sketch.veins[0][:, 2]
    profile = Profile.of_vein(shares, heights)
    assert len(profile.t) == 4
    np.testing.assert_allclose(profile.heights(shares), heights, atol=1e-12)


def test_a_long_veins_profile_has_a_few_handles_from_end_to_end():
    sketch = leaf_with_vein(11)
    profile = Profile.of_vein(sketch.vein_fractions(0), sketch.veins[0][:, 2])
    assert len(profile.t) == PROFILE_HANDLES
    assert profile.t[0] == 0.0 and profile.t[-1] == 1.0 and np.all(np.diff(profile.t) > 0)
    np.testing.assert_allclose(profile.h[[0, -1]], sketch.veins[0][[0, -1], 2])


def test_dragging_a_handle_reshapes_the_whole_vein_without_overshoot():
    sketch = leaf_with_vein(11)
    shares = sketch.vein_fractions(0)
    profile = Profile.of_vein(shares, sketch.veins[0][:, 2]).moved(2, 0.5, 0.12)
    after = sketch.with_heights(0, profile.heights(shares))
    heights = after.veins[0][:, 2]
    np.testing.assert_array_equal(after.veins[0][:, :2], sketch.veins[0][:, :2])  # only heights
    assert np.isclose(heights.max(), 0.12, atol=1e-3)  # the point under the handle went up
    assert np.all(heights <= profile.h.max() + 1e-12) and np.all(heights >= profile.h.min() - 1e-12)
    assert np.all(np.diff(heights[: int(np.argmax(heights)) + 1]) >= -1e-12)  # rises to the peak


def test_end_handles_move_up_and_down_only_and_inner_ones_stay_between_neighbours():
    profile = Profile(np.array([0.0, 0.3, 0.6, 1.0]), np.zeros(4))
    assert profile.moved(0, 0.4, 0.1).t[0] == 0.0
    assert profile.moved(3, 0.2, 0.1).t[-1] == 1.0
    assert np.isclose(profile.moved(1, 0.9, 0.0).t[1], 0.6 - MIN_GAP)
    assert np.isclose(profile.moved(2, -1.0, 0.0).t[2], 0.3 + MIN_GAP)
    crowded = Profile(np.array([0.0, 0.5, 0.51, 0.52, 1.0]), np.zeros(5))  # closer than the gap
    moved = crowded.moved(2, 0.9, 0.1)
    assert moved.t[2] == 0.51 and moved.h[2] == 0.1 and np.all(np.isfinite(moved.heights([0.5])))


def test_a_linear_profile_uses_the_same_shares_as_the_side_view():
    sketch = leaf_with_vein(5)
    linear = sketch.with_profile(0, 0.08, 0.02)
    np.testing.assert_allclose(linear.veins[0][:, 2], 0.08 - 0.06 * sketch.vein_fractions(0))


def test_a_profile_drag_is_one_undo_step_in_the_session():
    session = Session()
    sketch = leaf_with_vein(8)
    session.open_document(None, sketch, "drawn")
    before = session.state.sketch.veins[0][:, 2].copy()
    shares = sketch.vein_fractions(0)
    profile = Profile.of_vein(shares, before)
    steps = session.history.count()
    for h in (0.06, 0.09, 0.11):  # the drag's moves, each shown live
        profile = profile.moved(2, profile.t[2], h)
        session.preview_sketch(session.state.sketch.with_heights(0, profile.heights(shares)))
    session.commit_sketch(session.state.sketch, "Vein profile")
    assert session.history.count() == steps + 1
    assert not np.allclose(session.state.sketch.veins[0][:, 2], before)
    session.undo()
    np.testing.assert_array_equal(session.state.sketch.veins[0][:, 2], before)


def test_undoing_the_first_edit_of_a_loaded_leaf_shows_its_own_sketch_again():
    """A loaded leaf is edited through the sketch derived from its result; undoing the first
    edit (a vein profile, or any) must hand the editor that sketch back, not leave the edited
    one on screen while the document has gone back."""
    from tests.gui.builders import Runner
    from tests.gui.model.test_session import FAST

    runner = Runner()
    session = Session(runner, FAST)
    session.open_document(demo("nested"), None, "nested")
    runner.finish(session)
    derived = session.editable_sketch()
    assert derived is not None and len(derived.veins)
    shown = []
    session.sketch_shown.connect(lambda sketch, fit: shown.append(sketch))
    edited = derived.with_profile(0, 0.1, 0.0)
    session.preview_sketch(edited)
    session.commit_sketch(edited, "Vein profile")
    session.undo()
    assert session.state.sketch is None and shown and shown[-1] is derived


# --- the side view in the window (Xvfb) --------------------------------------------------------


def test_the_side_views_ends_say_which_is_the_base_of_a_midrib_written_apex_first():
    """The side view said "base" under its left end, where a midrib written apex first starts
    at its tip (the length, the placement and the 3D view take it base first)."""
    leaf = make_form("ovate")
    given = Sketch(boundary=leaf.boundary[:, :2], veins=tuple(leaf.veins))
    turned = Sketch(boundary=leaf.boundary[:, :2], veins=(leaf.veins[0][::-1], *leaf.veins[1:]))
    assert end_words(given, 0) == ("base", "tip")
    assert end_words(turned, 0) == ("tip", "base")
    assert end_words(turned, 1) == ("base", "tip")  # a side vein runs from the midrib
    assert end_words(turned, BOUNDARY) == ("point 1", "round to point 1")
