"""The user stories on the session model alone, without Qt: drawing, framing, vein branches,
crossings, orientation and colours, undo of parameters (issue 12's findings 1-6)."""

from __future__ import annotations

import sys
from itertools import pairwise

import numpy as np
import pytest
import shapely

from leafstudio.core.pipeline import Pipeline
from leafstudio.core.prepare.polygon import ring_crossings
from leafstudio.gui.model.framing import (
    best_iso,
    blade_bounds,
    fit_camera,
    projected_fill,
    view_direction,
)
from leafstudio.gui.model.session import Session
from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.model import Leaf, Params
from leafstudio.sources.demos import demo
from leafstudio.workflows import boundary_crossing
from tests.gui.builders import Runner
from tests.leaves import sketch_ellipse as ellipse

FAST = Params(k=3, grid=40, samples=1200)


@pytest.fixture
def runner() -> Runner:
    return Runner()


@pytest.fixture
def session(runner) -> Session:
    return Session(runner, FAST)


def events(session: Session) -> dict[str, list]:
    got: dict[str, list] = {"result": [], "failed": [], "sketch": [], "crossing": []}
    session.result_shown.connect(lambda outcome, framing: got["result"].append(framing))
    session.failed.connect(lambda message, fell_back: got["failed"].append(message))
    session.sketch_shown.connect(lambda sketch, fit: got["sketch"].append(fit))
    session.crossing.connect(lambda points: got["crossing"].append(len(points)))
    return got


def draw(session: Session, sketch: Sketch, points: np.ndarray) -> Sketch:
    """Add boundary points one click at a time, as the editor commits them."""
    for xy in points:
        sketch, _ = sketch.inserted(-1, xy)
        session.commit_sketch(sketch, "Add point")
    return sketch


def test_no_qt_is_imported_by_the_session_model():
    import subprocess

    code = (
        "import sys, leafstudio.gui.model.session, leafstudio.gui.model.framing; "
        "print(any(m.startswith(('PySide6', 'vtk', 'pyvista')) for m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


# --- finding 1: the sketch view jumps -----------------------------------------------------------
def test_drawing_never_asks_the_sketch_view_to_fit(session, runner):
    got = events(session)
    session.new_sketch()
    assert got["sketch"] == [True]  # a new document is fitted once
    draw(session, Sketch(), ellipse(5))
    runner.finish(session)
    assert got["sketch"][0] and not any(got["sketch"][1:])  # results and edits do not fit it
    assert session.leaf is not None and len(got["result"]) == 1


def test_every_change_of_the_documents_sketch_is_sent_to_the_editor(session, runner):
    """Review s3 finding 2: a sketch committed from outside the editor (Grow veins) was never
    sent to it, so the editor's next edit started from the old sketch and undid it."""
    shown: list = []
    session.sketch_shown.connect(lambda sketch, fit: shown.append((sketch, fit)))
    session.new_sketch()
    drawn = draw(session, Sketch(), ellipse(6))
    grown = drawn.with_vein(np.array([[0.1, 0.0, 0.0], [0.9, 0.0, 0.0]]))
    session.commit_sketch(grown, "Grow veins")
    assert shown[-1] == (grown, False)
    session.set_symmetric(True)
    assert shown[-1] == (session.state.sketch, False) and shown[-1][0].symmetric
    session.undo()
    assert shown[-1][0] is grown


# --- finding 2: the 3D camera frames every document, keeps the user's camera otherwise ----------
def test_each_document_is_framed_and_parameter_changes_keep_the_camera(session, runner):
    got = events(session)
    session.open_document(demo("nested"), None, "nested")
    runner.finish(session)
    assert got["result"][-1] is not None and got["result"][-1].reset
    session.set_params(FAST.with_(k=5))
    runner.finish(session)
    assert got["result"][-1] is None  # K changed: the camera stays
    session.open_document(demo("parallel"), None, "parallel")
    runner.finish(session)
    framing = got["result"][-1]
    assert framing is not None and framing.reset  # the parallel leaf framed, not the nested one
    size = framing.bounds.hi - framing.bounds.lo
    assert size[1] > 0.6 * size[0]  # the parallel demo is broad: its own bounds


def test_a_growing_sketch_is_reframed_and_the_first_triangle_does_not_stick(session, runner):
    got = events(session)
    session.new_sketch()
    small = draw(session, Sketch(), ellipse(8, 0.1, 0.05)[:3])
    runner.finish(session)
    assert got["result"][-1].reset
    draw(session, small, ellipse(12)[[0, 3, 6, 9]])
    runner.finish(session)
    framing = got["result"][-1]
    assert framing is not None and not framing.reset  # same direction, refitted
    assert framing.bounds.hi[0] - framing.bounds.lo[0] > 0.9  # the whole leaf


def test_robust_bounds_ignore_far_outliers_and_a_thin_stalk():
    rng = np.random.default_rng(1)
    frame = Sketch().frame
    blade = np.column_stack([rng.uniform(0, 1, 5000), rng.uniform(-0.2, 0.2, 5000), np.zeros(5000)])
    stalk = np.column_stack([np.linspace(-0.6, 0, 40), np.zeros(40), np.zeros(40)])
    outliers = np.array([[9.0, 9.0, 9.0], [-7.0, 3.0, -5.0]])
    bounds = blade_bounds(np.vstack([blade, stalk, outliers]), frame)
    assert bounds.lo[0] > -0.15 and bounds.hi[0] < 1.1 and bounds.hi[2] < 0.1


@pytest.mark.parametrize("name", ["nested", "parallel"])
def test_the_iso_camera_fills_the_view_both_ways(name):
    leaf = demo(name)
    result = Pipeline(leaf).run(FAST)
    bounds = blade_bounds(result.triangle_mesh.points, result.frame)
    for aspect in (0.8, 1.3, 1.8):
        direction, up = best_iso(bounds, 30.0, aspect)
        position, focus, up = fit_camera(bounds, direction, up, 30.0, aspect)
        wide, high = projected_fill(bounds, position, focus, up, 30.0, aspect)
        assert max(wide, high) >= 0.6 and min(wide, high) >= 0.35, (aspect, wide, high)


# --- finding 3: a new vein started on a vein branches from it ----------------------------------
def test_a_new_vein_snaps_onto_the_vein_it_starts_on():
    midrib = np.array([[0.0, 0.0, 0.05], [0.5, 0.02, 0.06], [1.0, 0.0, 0.05]])
    sketch = Sketch(boundary=ellipse(), veins=(midrib,))
    snapped = sketch.snap_to_vein(np.array([0.3, 0.012]), tolerance=0.02)
    assert snapped is not None
    near = shapely.LineString(sketch.vein_curve(0)[:, :2]).distance(shapely.Point(snapped[:2]))
    assert near < 1e-9 and 0.05 <= snapped[2] <= 0.06
    assert sketch.snap_to_vein(np.array([0.3, 0.15]), tolerance=0.02) is None
    branch = sketch.with_vein(snapped[None, :])
    again = branch.with_vein(snapped[None, :])  # two veins from one spot stay two veins
    assert len(again.veins) == 3 and np.array_equal(again.veins[0], midrib)


def test_no_empty_vein_is_kept_and_colours_follow_the_vein_index():
    sketch = Sketch(boundary=ellipse(), veins=(np.array([[0.1, 0, 0.05], [0.9, 0, 0.05]]),))
    sketch = sketch.with_vein(np.array([[0.4, 0.0, 0.05]])).deleted(1, 0)
    assert len(sketch.veins) == 1
    stored = sketch.to_dict()
    stored["veins"].insert(0, [])  # an old project with an empty vein first
    loaded = Sketch.from_dict(stored)
    assert len(loaded.veins) == 1 and len(loaded.to_leaf().veins) == len(loaded.veins)


# --- finding 4: a self-crossing boundary ---------------------------------------------------------
def test_a_crossing_sketch_is_not_reconstructed_and_says_where(session, runner):
    got = events(session)
    session.open_document(None, Sketch(boundary=ellipse()), "drawn")
    runner.finish(session)
    shown, requested = session.result, len(runner.requests)
    bow = ellipse()
    bow[[2, 8]] = bow[[8, 2]]  # two points swapped: the outline crosses itself
    session.preview_sketch(Sketch(boundary=bow))
    assert len(runner.requests) == requested  # nothing sent: the 3D view keeps its leaf
    assert session.result is shown and got["crossing"][-1] >= 1
    assert "crosses itself near" in got["failed"][-1]
    session.commit_sketch(Sketch(boundary=ellipse()), "Move point")
    assert len(runner.requests) == requested + 1 and got["crossing"][-1] == 0


def test_a_loaded_boundary_that_crosses_itself_is_found():
    points = np.column_stack([ellipse(40), np.zeros(40)])
    assert boundary_crossing(Leaf(points)) is None
    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)  # a figure of eight, crossing at (0, 0)
    eight = np.column_stack([np.cos(t), 0.3 * np.sin(2 * t), np.zeros(60)])
    where = boundary_crossing(Leaf(eight))
    assert where is not None and np.linalg.norm(where) < 0.05
    shuffled = np.random.default_rng(0).permutation(np.column_stack([ellipse(40), np.zeros(40)]))
    assert boundary_crossing(Leaf(shuffled)) is None  # an unordered cloud is not read in order
    assert len(ring_crossings(ellipse(40))) == 0


@pytest.mark.parametrize(("scale", "offset"), [(1.0, 1e9), (1.0, 1e12), (1e300, 0.0), (1e-90, 0.0)])
def test_a_boundary_far_away_or_at_any_scale_is_no_crossing(scale, offset):
    """The app opens a leaf through workflows.open_file, which checks the boundary for crossings
    in the world's units: the nested demo moved 1e9 away was refused ("crosses itself near
    (1e+09, ...)", where `reconstruct` takes it), and at 1e300 ended in "ValueError: data must
    be finite"; the check runs at unit size, as the pipeline does."""
    leaf = demo("nested")
    moved = Leaf(leaf.boundary * scale + offset, [v * scale + offset for v in leaf.veins])
    assert boundary_crossing(moved) is None
    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)  # a figure of eight, crossing at (0, 0)
    eight = np.column_stack([np.cos(t), 0.3 * np.sin(2 * t), np.zeros(60)]) * scale + offset
    where = boundary_crossing(Leaf(eight))
    assert where is not None and np.linalg.norm((where - offset) / scale) < 0.05


# --- finding 5: the same way round, the same colours --------------------------------------------
def test_the_top_view_shows_the_plane_as_the_sketch_does(session, runner):
    session.open_document(None, Sketch(boundary=ellipse()), "drawn")
    runner.finish(session)
    frame = session.view_frame()
    assert frame is session.state.sketch.frame
    direction, up = view_direction("top", frame)
    right = np.cross(up, direction)  # the screen's x axis for a camera looking along -direction
    np.testing.assert_allclose(right, frame.u, atol=1e-12)  # sketch x to the right
    np.testing.assert_allclose(up, frame.v, atol=1e-12)  # sketch y up


# --- finding 6: parameter changes are undone one release at a time ------------------------------
def test_each_parameter_change_is_one_undo_step(session, runner):
    session.open_document(demo("nested"), None, "nested")
    assert not session.is_modified()
    session.set_params(FAST.with_(k=7))
    assert session.history.count() == 1 and session.history.undo_text() == "Change K"
    assert session.is_modified()
    for k in (4, 5, 6):  # a slider drag: shown live, one step on release
        session.set_params(FAST.with_(k=k), final=False)
    session.set_params(FAST.with_(k=6), final=True)
    assert session.history.count() == 2 and runner.requests[-1][1].k == 6
    session.undo()
    assert session.params.k == 7 and runner.requests[-1][1].k == 7
    session.undo()
    assert session.params.k == 3 and not session.is_modified()
    session.redo()
    assert session.params.k == 7


def test_a_new_document_is_one_undo_step_and_a_failed_open_falls_back(session, runner):
    session.open_document(demo("nested"), None, "nested")
    runner.finish(session)
    nested = session.leaf
    session.new_document(demo("parallel"), title="parallel")  # e.g. from the forms gallery
    assert session.history.undo_text() == "New leaf: parallel"
    session.undo()
    assert session.leaf is nested
    line = Leaf(boundary=[[t, 2 * t, 0] for t in np.linspace(0, 1, 20)])
    got = events(session)
    session.open_document(line, None, "line.csv", path="line.csv")
    runner.finish(session)
    assert session.leaf is nested and session.state.path is None  # back to the demo
    assert got["failed"] and "line" in got["failed"][-1]


# --- mirror editing and whole-vein profiles (no Qt) ---------------------------------------------
def test_mirroring_reflects_the_edited_half_about_the_midrib():
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    lopsided = np.column_stack([0.5 + 0.5 * np.cos(t), 0.2 * np.sin(t) * (1 + 0.5 * np.sin(t))])
    midrib = np.array([[0.0, 0.0, 0.05], [1.0, 0.0, 0.05]])
    side = np.array([[0.4, 0.0, 0.05], [0.6, 0.15, 0.04]])
    sketch = Sketch(boundary=lopsided, veins=(midrib, side))
    mirrored = sketch.mirrored(+1.0)  # keep the upper half
    upper = mirrored.boundary[mirrored.boundary[:, 1] > 1e-9]
    lower = mirrored.boundary[mirrored.boundary[:, 1] < -1e-9]
    np.testing.assert_allclose(np.sort(upper[:, 0]), np.sort(lower[:, 0]))
    np.testing.assert_allclose(np.sort(upper[:, 1]), np.sort(-lower[:, 1]))
    assert len(ring_crossings(mirrored.boundary_curve())) == 0  # still one loop around
    assert len(mirrored.veins) == 3
    np.testing.assert_allclose(mirrored.veins[2][:, 1], -side[:, 1])
    again = mirrored.mirrored(+1.0)  # a second edit replaces the mirror, does not add one
    assert len(again.veins) == 3


def test_a_whole_vein_profile_is_linear_along_the_vein():
    vein = np.array([[0.0, 0.0, 0.1], [0.25, 0.0, 0.3], [1.0, 0.0, 0.0]])
    sketch = Sketch(boundary=ellipse(), veins=(vein,)).with_profile(0, 0.08, 0.02)
    np.testing.assert_allclose(sketch.veins[0][:, 2], [0.08, 0.065, 0.02])
    np.testing.assert_array_equal(sketch.veins[0][:, :2], vein[:, :2])


# --- review s3 finding 3: undo, redo or a new document during an edit (no Qt) --------------------
def assert_chained(session: Session) -> None:
    """Each undo step starts from exactly the state the one before it led to."""
    steps = session.history.steps
    for earlier, later in pairwise(steps):
        assert later.before is earlier.after, (earlier.text, later.text)


def nudged(sketch: Sketch, dy: float) -> Sketch:
    """`sketch` with its first boundary point moved by `dy` (a drag's preview)."""
    return sketch.moved(-1, 0, sketch.boundary[0] + [0.0, dy])


@pytest.mark.parametrize("move", ["undo", "redo"])
def test_an_undo_or_redo_during_a_drag_leaves_it_no_base_from_before(session, move):
    """A drag under way (its first preview set the session's edit base) when Ctrl+Z or Ctrl+Y
    comes: the base was kept, so the next edit's step went from the state before the undo (or
    redo) and undoing it brought back what the user had undone."""
    drawn = draw(session, Sketch(), ellipse(6))
    session.set_params(FAST.with_(k=5))  # "Change K": 3 -> 5
    if move == "redo":
        session.undo()
    session.preview_sketch(nudged(drawn, 0.05))  # a drag begins
    getattr(session, move)()
    assert session.params.k == (3 if move == "undo" else 5)
    moved_to = session.state
    later = nudged(drawn, -0.05)  # the next drag
    session.preview_sketch(later)
    session.commit_sketch(later, "Move point")
    assert session.history.steps[-1].before is moved_to
    assert_chained(session)
    session.undo()
    assert session.state is moved_to  # K 5 after undo was 3: the undone change came back


def test_an_undo_during_a_slider_drag_leaves_it_no_base_from_before(session):
    session.open_document(demo("nested"), None, "nested")
    session.set_params(FAST.with_(k=5))  # "Change K": 3 -> 5
    session.set_params(FAST.with_(k=6), final=False)  # a slider held
    session.undo()
    assert session.params.k == 3
    session.set_params(FAST.with_(k=4), final=True)  # let go further on
    assert session.history.steps[-1].before.params.k == 3
    session.undo()
    assert session.params.k == 3  # was 5: the undone change came back
    session.set_params(FAST.with_(k=6), final=False)
    session.redo()  # a redo while held: the step it makes current is not dropped or amended
    assert session.params.k == 4 and session.history.count() == 1
    session.set_params(FAST.with_(k=7), final=True)
    assert_chained(session)
    assert session.history.steps[-1].before.params.k == 4


@pytest.mark.parametrize("undoable", [True, False])
def test_a_new_document_during_an_edit_starts_from_before_it(session, runner, undoable):
    """A new document opened while a drag or a slider is held: its undo step (or the document
    a failed open falls back to) is the state before the unfinished edit, never its preview."""
    drawn = draw(session, Sketch(), ellipse(6))
    runner.finish(session)
    committed = session.state
    session.preview_sketch(nudged(drawn, 0.05))
    session.set_params(FAST.with_(k=6), final=False)
    line = Leaf(boundary=[[t, 2 * t, 0] for t in np.linspace(0, 1, 20)])  # fails to open
    session.new_document(line if not undoable else demo("parallel"), undoable=undoable)
    assert session.params.k == 3  # the held slider's value went with its drag
    if undoable:
        assert session.history.steps[-1].before is committed
        assert_chained(session)
        session.undo()
    else:
        runner.finish(session)  # the line fails: the previous document comes back
    assert session.state is committed
