"""Mirror editing as a property of the drawing (issue 12 leftovers), on the session model (no
Qt): the symmetric flag is saved in the project, comes back on open, is an undo step that marks
the document modified, and a project that has it still loads in the command line and the API; a
midrib bent more tightly than the leaf is wide is not mirrored."""

from __future__ import annotations

import json

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.cli import main
from leafstudio.core.prepare.polygon import ring_crossings
from leafstudio.gui.model.session import Session
from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.sources.files import load_project, save_leaf
from tests.gui.builders import Runner
from tests.gui.model.test_session import FAST, ellipse


def drawn_leaf(symmetric: bool = False) -> Sketch:
    """An ellipse with a straight midrib along its long axis."""
    midrib = np.array([[0.05, 0.0, 0.04], [0.5, 0.0, 0.04], [0.95, 0.0, 0.04]])
    return Sketch(boundary=ellipse(), veins=(midrib,), symmetric=symmetric)


def save_session(session: Session, path) -> None:
    """What File > Save writes (main_window.save_to)."""
    state = session.state
    save_leaf(state.leaf, path, state.params, state.sketch.to_dict())
    session.saved(str(path))


def test_a_sketch_saved_with_mirror_on_opens_with_mirror_on(tmp_path):
    session = Session(Runner(), FAST)
    session.new_sketch()
    session.commit_sketch(drawn_leaf(), "Draw")
    session.set_symmetric(True)
    path = tmp_path / "mirror.leaf.json"
    save_session(session, path)
    assert json.loads(path.read_text())["sketch"]["symmetric"] is True
    _, _, stored = load_project(path)
    assert Sketch.from_dict(stored).symmetric

    reopened = Session(Runner(), FAST)
    shown = []
    reopened.sketch_shown.connect(lambda sketch, fit: shown.append(sketch))
    reopened.open_document(None, Sketch.from_dict(stored), path.name, path=str(path))
    assert reopened.state.sketch.symmetric and shown[-1].symmetric  # the editor shows it on
    assert not reopened.is_modified()


def test_a_project_without_the_flag_means_off_and_a_bad_flag_is_refused():
    stored = drawn_leaf().to_dict()
    del stored["symmetric"]  # a project written before the flag
    assert Sketch.from_dict(stored).symmetric is False
    for bad in ("yes", 1, None):
        with pytest.raises(ValueError, match="symmetric"):
            Sketch.from_dict({**stored, "symmetric": bad})


def test_turning_mirror_on_is_an_undo_step_that_marks_the_document_modified(tmp_path):
    runner = Runner()
    session = Session(runner, FAST)
    session.new_sketch()
    session.commit_sketch(drawn_leaf(), "Draw")
    save_session(session, tmp_path / "a.leaf.json")
    requests = len(runner.requests)
    leaf = session.leaf
    shown = []
    session.sketch_shown.connect(lambda sketch, fit: shown.append(sketch.symmetric))

    session.set_symmetric(True)
    assert session.state.sketch.symmetric and session.is_modified()
    assert session.history.undo_text() == "Mirror on"
    assert session.leaf is leaf and len(runner.requests) == requests  # nothing to reconstruct
    assert shown == [True]
    session.set_symmetric(True)  # no change: no step
    assert session.history.undo_text() == "Mirror on" and session.history.count() == 2

    session.undo()
    assert not session.state.sketch.symmetric and not session.is_modified()
    assert shown[-1] is False  # the editor's checkbox follows
    session.redo()
    assert session.state.sketch.symmetric and shown[-1] is True
    # an edit made with Mirror on keeps it on (sketch edits carry the flag)
    session.commit_sketch(session.state.sketch.moved(-1, 0, [1.0, 0.0]), "Move point")
    assert session.state.sketch.symmetric


def test_mirror_on_a_loaded_leaf_waits_for_its_first_edit(tmp_path):
    """A loaded leaf has no sketch of its own until it is edited (its sketch is derived from its
    result): ticking Mirror does not turn the leaf into that approximation (which would change
    the mesh); the first edit, which does, carries the flag."""
    runner = Runner()
    session = Session(runner, FAST)
    session.open_document(ls.demo("nested"), None, "nested")
    runner.finish(session)
    leaf = session.leaf
    session.set_symmetric(True)
    assert session.state.sketch is None and session.leaf is leaf
    assert session.editable_sketch().symmetric and not session.is_modified()
    edit = session.editable_sketch().moved(-1, 0, session.editable_sketch().boundary[0] * 1.01)
    session.commit_sketch(edit, "Move point")
    assert session.state.sketch.symmetric


def test_a_project_with_the_flag_loads_in_the_api_and_the_command_line(tmp_path, capsys):
    path = tmp_path / "sym.leaf.json"
    sketch = drawn_leaf(symmetric=True)
    save_leaf(sketch.to_leaf(), path, FAST, sketch.to_dict())
    leaf = ls.load_leaf(path)
    assert len(leaf.boundary) == len(sketch.to_leaf().boundary)
    assert main(["measure", str(path), "--json", "--grid", "32"]) == 0
    assert "area" in capsys.readouterr().out


# --- a midrib bent more tightly than the leaf is wide (no Qt) ---------------------------------
def bent_leaf(radius: float, outside: float, inside: float, sweep: float = 0.9 * np.pi) -> Sketch:
    """A leaf along a midrib on a circular arc of `radius` about the origin, turning left (its
    left is the inside of the bend): `outside` wide on the right, `inside` on the left."""
    a = np.linspace(-sweep / 2, sweep / 2, 7)
    midrib = np.column_stack([radius * np.cos(a), radius * np.sin(a), np.full(7, 0.03)])
    t = np.linspace(0, 1, 16)
    around = np.column_stack([np.cos(-sweep / 2 + sweep * t), np.sin(-sweep / 2 + sweep * t)])
    width = np.sin(np.pi * t) ** 0.7
    right = (radius + outside * width)[:, None] * around
    left = (radius - inside * width)[:, None] * around
    return Sketch(boundary=np.vstack([right, left[::-1][1:-1]]), veins=(midrib,), symmetric=True)


def test_a_midribs_bend_is_measured_by_its_radius_of_curvature():
    sketch = bent_leaf(radius=1.0, outside=0.5, inside=0.2)
    midrib = sketch.midrib()
    angle = np.linspace(-0.3, 0.3, 5)
    for offset in (0.3, -0.6):  # + left: inside the bend
        points = (1.0 - offset) * np.column_stack([np.cos(angle), np.sin(angle)])
        reach, d, feet = midrib.mirror_reach(points)
        np.testing.assert_allclose(d, offset, atol=1e-3)
        np.testing.assert_allclose(-d / reach, 1.0, rtol=0.05)  # the radius of curvature
        np.testing.assert_allclose(reach, -offset, rtol=0.05)  # the image's depth into the bend
        np.testing.assert_allclose(np.linalg.norm(feet, axis=1), 1.0, atol=1e-3)


def test_a_sketch_with_only_a_midrib_has_no_fold():
    midrib = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    assert Sketch(boundary=[[0.5, 0.2]], veins=(midrib,)).mirror_fold(1.0) is None
    assert Sketch(veins=(midrib,)).mirror_edit(np.array([0.5, 0.1]))[1] is None


def test_a_mirror_that_would_fold_is_not_made_and_says_why():
    """Before: the wide outer half was reflected past the centre of the bend into a folded,
    self-crossing boundary, without a word."""
    sketch = bent_leaf(radius=1.0, outside=1.3, inside=0.3)
    outer = np.array([1.6, 0.0])  # an edit on the right, the outside of the bend
    folded = sketch.mirrored(-1.0)
    assert len(ring_crossings(folded.boundary_curve())) > 0  # what mirroring used to make
    kept, fold = sketch.mirror_edit(outer)
    assert kept is sketch  # the edit stays as it is, not mirrored
    assert fold is not None and fold.radius < fold.reach
    assert fold.radius == pytest.approx(1.0, rel=0.05) and fold.reach == pytest.approx(1.3, 0.02)
    assert np.hypot(*fold.where) == pytest.approx(1.0, abs=1e-3)  # a point on the midrib
    message = fold.message()
    assert "Not mirrored" in message and f"{fold.radius:.3g}" in message
    # from the narrow inside the mirror fits: made, nothing said
    inner_edit, none = sketch.mirror_edit(np.array([0.8, 0.0]))
    assert none is None and inner_edit is not sketch
    assert len(ring_crossings(inner_edit.boundary_curve())) == 0


@pytest.mark.parametrize(("outside", "folds"), [(0.8, False), (1.15, True)])
def test_the_fold_is_found_where_the_leaf_reaches_past_the_bends_centre(outside, folds):
    sketch = bent_leaf(radius=1.0, outside=outside, inside=0.3)
    assert (sketch.mirror_fold(-1.0) is not None) == folds
    assert sketch.mirror_fold(+1.0) is None  # the inside half mirrors onto the outside
