"""A pose fitted by a run to the document's curves in 3D is the document's (gui/model/pose_fits.py):
the view showed it bent while the document kept the leaf unbent, its sliders at 0, and Save,
Undo and a slider acted on a pose not on screen. Edit > Fit pose again fits a refused leaf once
more, as one undo step."""

from __future__ import annotations

from collections import OrderedDict

import numpy as np
import pytest

import leafstudio.core.unfold as unfold
import leafstudio.core.unfolded as unfolded
from leafstudio.core.pipeline import Pipeline
from leafstudio.core.placed import PlacedPose
from leafstudio.core.unfolded import as_given
from leafstudio.forms import Form, make_form
from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.model import Leaf
from leafstudio.sources.files import load_project, save_leaf
from tests.gui.builders import FAST
from tests.leaves import cupped_ovate

from .test_session_files import opened_session


@pytest.fixture
def fits(monkeypatch) -> list:
    """The fits run (unfold._fit, past unfold_checks.bent's gate), one entry each; the curves
    remembered as needing no bend (core/unfolded.py) this test's own: a refusal here is not
    another test's (the same ovate folded 60, the same cup)."""
    monkeypatch.setattr(unfolded, "_UNBENT", OrderedDict())
    done: list = []
    fit = unfold._fit
    monkeypatch.setattr(unfold, "_fit", lambda *a, **k: done.append(1) or fit(*a, **k))
    return done


def folded_curves(monkeypatch) -> tuple[Leaf, Sketch]:
    """Ovate folded 60 as curves in 3D without a pose, and the sketch that draws them as given
    (its outline seen from above, their heights its relief): what a user's edit of a loaded
    leaf's sketch may make of it."""
    form = Form("ovate", fold=60.0).leaf()
    folded = Leaf(form.boundary, form.veins)
    drawn = Sketch.from_result(Pipeline(as_given(folded)).run(FAST))
    monkeypatch.setattr(unfolded, "_UNBENT", OrderedDict())  # forgotten: fitted as any curves
    return folded, drawn


def flat_width(sketch: Sketch) -> float:
    """The width across the sketch's plane of the leaf it draws."""
    return float(np.ptp(sketch.frame.to_plane(sketch.to_leaf().boundary)[0][:, 1]))


def opened_cup(tmp_path, monkeypatch):
    """A session with the cup 0.6 deep opened from a CSV (its pose fit refused), and the sketch
    of ovate folded 60's curves an edit may draw (folded_curves)."""
    _, drawn = folded_curves(monkeypatch)
    path = tmp_path / "cup.csv"
    save_leaf(cupped_ovate(0.6), path)
    session, runner, _ = opened_session()
    session.open_path(str(path))
    runner.finish(session)
    return session, runner, drawn


def test_a_pose_fitted_to_an_edited_leaf_is_the_documents(tmp_path, fits, monkeypatch):
    """The cup 0.6 deep opened as a CSV (refused), then an edit whose curves a pose lays flat:
    the run fits it once, and the document takes it: its sliders read the fold, its sketch
    draws the flat blade, Save writes the pose, a K change fits nothing again (it fitted each
    time: the worker's pipeline was for the unbent leaf), Undo goes back to the cup and Redo
    to the fitted leaf without a fit."""
    session, runner, drawn = opened_cup(tmp_path, monkeypatch)
    cup, shares = session.state, session.state.unposed
    assert cup.leaf.bend is None and shares is not None
    fits.clear()
    session.commit_sketch(drawn, "Draw folded")
    runner.finish(session)
    assert len(fits) == 1 and isinstance(session.result.leaf.bend, PlacedPose)
    assert session.leaf is session.result.leaf  # the document's, not the view's alone
    assert abs(abs(session.pose.fold) - 60.0) < 1.5, session.pose
    assert session.state.unposed is None
    sketch = session.state.sketch  # the flat blade's: posed again, it is not bent twice
    assert flat_width(sketch) > 0.98 * np.ptp(make_form("ovate").boundary[:, 1])
    assert session.sketch_leaf(sketch).bend is not None
    save_leaf(session.leaf, tmp_path / "saved.leaf.json", session.params, sketch.to_dict())
    assert load_project(tmp_path / "saved.leaf.json")[0].bend is not None
    session.set_params(session.params.with_(k=4))
    runner.finish(session)
    assert len(fits) == 1 and session.result.leaf is session.leaf
    session.undo()
    session.undo()
    assert session.state is cup and session.history.can_redo()
    runner.finish(session)
    assert session.result.leaf.bend is None and len(fits) == 1  # the refusal kept
    session.redo()
    runner.finish(session)
    assert isinstance(session.leaf.bend, PlacedPose) and session.result.leaf is session.leaf
    assert len(fits) == 1


def test_a_fit_due_during_a_sketch_drag_is_taken_at_its_end(tmp_path, fits, monkeypatch):
    """A drag's preview fitted: its pose waits for the drag's end (its next preview would have
    bent the sketch of the bent curves by it), and is then the document's."""
    session, runner, drawn = opened_cup(tmp_path, monkeypatch)
    session.preview_sketch(drawn)
    runner.finish(session)
    assert session.leaf.bend is None and session.state.sketch is drawn  # held back
    session.commit_sketch(drawn, "Drag")  # the last preview's run is the edit's
    assert isinstance(session.leaf.bend, PlacedPose) and session.leaf is session.result.leaf
    assert session.history.steps[-1].after is session.state


def test_a_project_of_curves_in_3d_with_their_sketch_opens_with_their_pose(
    tmp_path, fits, monkeypatch
):
    """Such an edit saved on main (its sketch, no pose) opened unbent: fitted twice (as it was
    read, then by its run), the view bent, the sliders at 0. It opens fitted, once, drawn by
    the sketch of its flat blade derived from its first result."""
    folded, drawn = folded_curves(monkeypatch)
    path = tmp_path / "folded.leaf.json"
    save_leaf(folded, path, FAST, drawn.to_dict())
    session, runner, _ = opened_session()
    session.open_path(str(path))
    assert isinstance(session.leaf.bend, PlacedPose) and session.state.sketch is None
    runner.finish(session)
    assert len(fits) == 1 and session.leaf is session.result.leaf
    assert abs(abs(session.pose.fold) - 60.0) < 1.5, session.pose
    assert flat_width(session.editable_sketch()) > 0.98 * np.ptp(make_form("ovate").boundary[:, 1])


def test_fit_pose_again_takes_a_fit_as_one_undo_step(tmp_path, fits, monkeypatch):
    """A leaf refused a pose (here: by a fit that found none, as an older fit did), its refusal
    kept; Fit pose again fits its curves once more on the worker: the fit is the document's as
    one undo step, and Undo brings the refused leaf back without fitting it again."""
    form = Form("ovate", fold=60.0).leaf()
    path = tmp_path / "folded.csv"
    save_leaf(Leaf(form.boundary, form.veins), path)
    counted = unfold._fit  # the fixture's: counts, then fits
    monkeypatch.setattr(unfold, "_fit", lambda *a, **k: fits.append(1))  # no pose found
    session, runner, _ = opened_session()
    said: list = []
    session.noticed.connect(said.append)
    session.fitting.connect(said.append)
    session.open_path(str(path))
    runner.finish(session)
    refused, derived = session.state, session.editable_sketch()
    assert refused.leaf.bend is None and refused.unposed is not None and derived is not None
    assert session.can_fit_pose()
    monkeypatch.setattr(unfold, "_fit", counted)
    fits.clear()
    steps = session.history.count()
    request = session.fit_pose_again()
    assert request == session.last_id and said == ["Fitting a pose to the leaf's 3D curves…"]
    assert session.state is refused  # nothing changes until the fit is back
    runner.finish(session)
    assert len(fits) == 1 and isinstance(session.leaf.bend, PlacedPose)
    assert session.leaf is session.result.leaf and session.state.unposed is None
    assert session.history.count() == steps + 1
    assert session.history.undo_text().startswith("Fit pose: fold 59.99")
    assert not session.can_fit_pose()  # posed
    assert flat_width(session.state.sketch) > 1.2 * flat_width(derived)  # the flat blade's
    shown: list = []
    session.sketch_shown.connect(lambda sketch, fit: shown.append(sketch))
    session.undo()
    assert session.state is refused and shown == [derived]  # its own sketch, as it was
    runner.finish(session)
    assert session.result.leaf.bend is None and len(fits) == 1


def test_fit_pose_again_refused_says_so_and_keeps_the_refusal(tmp_path, fits):
    """The cup refused again: said in the window (`noticed`), the refusal kept (no fit at the
    next edit), no undo step; the leaf shown is the document's still."""
    path = tmp_path / "cup.csv"
    save_leaf(cupped_ovate(0.6), path)
    session, runner, _ = opened_session()
    said: list = []
    session.noticed.connect(said.append)
    session.open_path(str(path))
    runner.finish(session)
    steps, fits[:] = session.history.count(), []
    assert session.fit_pose_again() > 0
    runner.finish(session)
    assert len(fits) == 1 and session.leaf.bend is None
    assert len(said) == 1 and said[0].startswith("No fold, curl, roll or twist lays"), said
    assert "14.2% of its width off its plane" in said[0]
    assert session.notes_of(session.shown_id) == said  # on the status line with its result
    assert session.leaf is session.result.leaf and session.state.unposed is not None
    assert session.history.count() == steps and session.editable_sketch() is not None
    sketch = session.editable_sketch()
    session.commit_sketch(sketch.moved(-1, 0, sketch.boundary[0] * 1.001), "Move point")
    runner.finish(session)
    assert len(fits) == 1


def test_fit_pose_again_is_off_where_there_is_nothing_to_fit(tmp_path, fits):
    """A drawn (flat) leaf, a leaf with its pose: nothing to fit, no request."""
    session, _, _ = opened_session()
    assert not session.can_fit_pose() and session.fit_pose_again() == 0  # no leaf
    session.open_demo("nested")
    assert not session.can_fit_pose() and session.fit_pose_again() == 0
    form = make_form("ovate", fold=45.0)
    path = tmp_path / "folded.csv"
    save_leaf(Leaf(form.boundary, form.veins), path)
    session.open_path(str(path))
    assert isinstance(session.leaf.bend, PlacedPose) and not session.can_fit_pose()


def _opened_refused(tmp_path, fits, monkeypatch):
    """A session with the curves of ovate folded 60 opened from a CSV while no pose is found
    (its refusal remembered), and a function that lets the pose fit find poses again."""
    form = Form("ovate", fold=60.0).leaf()
    path = tmp_path / "folded.csv"
    save_leaf(Leaf(form.boundary, form.veins), path)
    counted = unfold._fit
    monkeypatch.setattr(unfold, "_fit", lambda *a, **k: fits.append(1))  # no pose found
    session, runner, _ = opened_session()
    session.open_path(str(path))
    runner.finish(session)
    return session, runner, lambda: monkeypatch.setattr(unfold, "_fit", counted)


def test_an_undo_while_fit_pose_again_runs_keeps_the_redo_steps(tmp_path, fits, monkeypatch):
    """Fit pose again, then Undo (of Mirror on: the same leaf, no run of its own) before the fit
    is back: the fit's answer pushed its step from the undone state, and the Redo of Mirror on
    was gone. The Undo goes back past the request: its fit is dropped, the refusal kept, the
    redo steps kept, and the leaf shown is the document's again."""
    session, runner, fit_again = _opened_refused(tmp_path, fits, monkeypatch)
    sketch = session.editable_sketch()  # a sketch of its own: Mirror on is an undo step
    session.commit_sketch(sketch.moved(-1, 0, sketch.boundary[0] * 1.0001), "Move point")
    runner.finish(session)
    fit_again()
    session.set_symmetric(True)
    refused = session.state
    request = session.fit_pose_again()
    session.undo()
    assert session.history.redo_text() == "Mirror on"
    undone = session.state
    runner.finish(session, request - 1)
    assert session.history.redo_text() == "Mirror on" and session.history.count() == 2
    assert session.state is undone and session.leaf.bend is None
    runner.finish(session)  # the document's leaf run again, as given: its refusal kept
    assert session.result.leaf is session.leaf and session.result.leaf.bend is None
    session.redo()
    assert session.state is refused


def test_fit_pose_again_stopped_by_a_newer_change_says_so(tmp_path, fits, monkeypatch):
    """Fit pose again, then K changed before the fit is back: the newer run stops the fit's (the
    worker's interrupt) and is shown first, so the fit's answer is dropped; the leaf stayed
    unposed without a word (the real window: /work/notes/review39/gui_interleave.txt). Its
    result says so on the status line."""
    session, runner, fit_again = _opened_refused(tmp_path, fits, monkeypatch)
    fit_again()
    request = session.fit_pose_again()
    session.set_params(session.params.with_(k=4))
    runner.finish(session)  # the K change's run, shown first
    assert session.leaf.bend is None
    notes = session.notes_of(session.shown_id)
    assert any(n.startswith("Fit pose again was stopped") for n in notes), notes
    runner.finish(session, request - 1)  # older than the shown: dropped
    assert session.leaf.bend is None and session.history.undo_text() == "Change K"
