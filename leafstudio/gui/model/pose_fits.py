"""A pose fitted to the document's curves in 3D by its run, taken into the document (no Qt).

A leaf with no bend whose curves stand bent in 3D is unfolded by its Pipeline, on the worker
(core/unfolded.unfolded): the view showed the fitted pose bent while the document kept the leaf
unbent, its sliders at Fold 0, Curl 0, and a slider's move, Save or Undo acted on a pose not on
screen (the cup 0.6 deep, refused as opened, then edited into ovate folded 60; a project of such
curves, saved with their sketch and no pose, reopened). Each K change fitted it again too: the
worker keeps a Pipeline for the leaf it was asked, not the one it fitted (6.2 s of wall time a
change, /work/notes/refit39/repro.py). The run's answer is now the document's (`_take_pose`):
every snapshot of those curves (the state, the history's steps, an edit's base) takes the leaf
with its fitted pose, so the sliders show it, Save writes it and Undo goes back to before the
edit; a snapshot that had a sketch of its own takes the sketch of the flat blade, the worker's
(`pose_fitted`), as an opened file's fitted leaf is drawn: the sketch of the bent curves, posed
again, would be bent twice.

Edit > Fit pose again (`fit_pose_again`) fits the document's curves once more, forgetting a
refusal kept for them (history.State.unposed, bending.keeps_refusal): its run is asked for a
copy of the curves (core/unfolded.refit), its fit taken as one undo step, its refusal said
(`refused_text`) and kept again.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from leafstudio.core.unfolded import as_given, plane_share, refit, stands_unposed
from leafstudio.gui.model.bending import bend_text
from leafstudio.gui.model.history import State, Step
from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.model import Leaf

REFIT = "refit"  # a request's reason: Fit pose again's run
STOPPED = (
    "Fit pose again was stopped by a newer change before its fit was done: the leaf stays "
    "unposed (Edit > Fit pose again fits it)"
)


def pose_fitted(asked: Leaf, ran: Leaf) -> bool:
    """Whether a run asked for the leaf `asked` fitted it a pose: its Pipeline's leaf `ran` is a
    new Leaf with a bend (core/unfolded.unfolded; a leaf given its bend is run as it is)."""
    return asked.bend is None and ran is not asked and ran.bend is not None


def refused_text(leaf: Leaf) -> str:
    """What the window says when Fit pose again finds no pose for `leaf` (a cup)."""
    return (
        "No fold, curl, roll or twist lays this leaf's curves flat (its margin stands "
        f"{plane_share(leaf):.1%} of its width off its plane): it stays unposed and is "
        "reconstructed as its curves stand."
    )


class PoseFits:
    """The Session's taking of fitted poses (a mixin: Session has the state, history, events,
    `submit` and the requests)."""

    state: State
    history: Any
    _requested: dict[int, tuple[int, str, Leaf | None]]
    derived: Sketch | None
    _derived_leaf: Leaf | None
    _pose_due: tuple[int, Any] | None = None  # a run's fit held back by a sketch drag
    _told: tuple[int, str]  # a note said with a request's result (Session.notes_of)
    _refit_at: tuple[int, int] | None = None  # Fit pose again's request, the history's index then

    def can_fit_pose(self) -> bool:
        """Whether Fit pose again applies: the document's leaf has no bend and its curves stand
        bent in 3D (core/unfolded.stands_unposed), refused or not yet fitted; a scan's leaf has
        its sheet."""
        leaf = self.state.leaf
        return leaf is not None and self.state.scan is None and stands_unposed(leaf)

    def fit_pose_again(self) -> int:
        """Fit a pose to the document's curves once more, on the worker (its run's Pipeline
        unfolds them, core/unfolded.py), whatever refusal was kept for them; the request's id
        (0: nothing to fit, `can_fit_pose`). Its fit becomes the document as one undo step
        ("Fit pose: fold ..."); a refusal is said (`noticed`) and kept. An Undo past it before
        the fit is back drops the fit (`_refit_answered`): its step would throw the redo away."""
        if not self.can_fit_pose():
            return 0
        self._drop_edit()  # a drag under way: its base would bring the unposed leaf back
        leaf = self.state.leaf
        self.last_id = self.submit(refit(leaf), self.params, True)
        self._requested[self.last_id] = (self.state.serial, REFIT, leaf)
        self._refit_at = (self.last_id, self.history.index)
        self.fitting.emit("Fitting a pose to the leaf's 3D curves…")
        return self.last_id

    def _take_pose(self, request_id: int, outcome: Any) -> None:
        """Run `request_id`'s answer about its curves' pose (`outcome.result.leaf`) made the
        document's, when the document still draws those curves (module docstring). During a
        drag of the sketch it waits for the drag's end (`_take_due_pose`): the drag's next
        preview would bend its sketch of the bent curves by the pose."""
        asked = self._requested.get(request_id)
        leaf = None if asked is None else asked[2]
        undone = self._refit_answered(request_id, leaf)
        if leaf is None or self.state.leaf is not leaf:
            return
        explicit, result = asked[1] == REFIT, outcome.result
        ran = result.leaf
        if not (explicit or pose_fitted(leaf, ran)):
            return
        fitted = ran.bend is not None
        if explicit and fitted and undone:
            # its step would be pushed from a state undone to, the redo steps thrown away (Undo
            # of Mirror on while the fit ran: Redo had nothing left): the Undo drops the fit,
            # the refusal kept as it was, the document's leaf shown again (review39)
            as_given(leaf)
            self._request(reason="undo")
            return
        if self._edit_base is not None:
            self._pose_due = (request_id, outcome)
            return
        flat: list[Sketch] = []

        def taken(state: State, own: bool = False) -> State:
            """`state` holding the run's leaf: fitted, with the flat blade's sketch (the
            worker's, unless a test's runner's) where it had one of its own, or `own`."""
            drawn = state.sketch
            if fitted and (drawn is not None or own):
                made = flat or [getattr(outcome, "sketch", None) or Sketch.from_result(result)]
                flat[:] = made
                mirror = drawn if drawn is not None else self.editable_sketch()
                drawn = replace(made[0], symmetric=mirror is not None and mirror.symmetric)
            unposed = None if fitted else plane_share(ran)
            return replace(state, leaf=ran, sketch=drawn, unposed=unposed)

        before = self.state
        if explicit and fitted:  # one undo step of its own, drawn by a sketch of its own: Undo
            # to a loaded leaf drawn by its derived sketch finds that sketch as it was
            self.state = taken(before, own=True)
            text = bend_text(self.pose, self.half_width).removeprefix("Bend: ")
            self.history.push(Step(f"Fit pose: {text}", before, self.state))
        else:  # the edit's snapshots, or those refused again, hold the run's leaf
            self._swap(leaf, taken)
        if self._derived_leaf is leaf and not fitted:
            self._derived_leaf = ran  # the same curves: its derived sketch still draws them
        self.state_changed.emit(self.state, "fitted")
        if self.state.sketch is not None and self.state.sketch is not before.sketch:
            self.sketch_shown.emit(self.state.sketch, True)
        if explicit and not fitted:  # in a box, and on the status line with its result
            self._told = (request_id, refused_text(ran))
            self.noticed.emit(self._told[1])

    def _refit_answered(self, request_id: int, leaf: Leaf | None) -> bool:
        """Fit pose again's request forgotten once `request_id`, it or a newer run, is shown
        (an older answer is dropped: Session.accept_result). A newer run of the same leaf (a K
        change) stopped its fit on the worker: said with that run's result, the leaf unposed
        without a word otherwise (review39). Whether an Undo went back past Fit pose again
        before its own answer (`request_id`) came."""
        at, self._refit_at = self._refit_at, None
        if at is None or request_id < at[0]:
            self._refit_at = at
            return False
        refit_asked = self._requested.get(at[0])
        stopped = request_id > at[0] and refit_asked is not None and refit_asked[2] is leaf
        if stopped and self._told[0] != request_id:
            self._told = (request_id, STOPPED)
        return request_id == at[0] and self.history.index < at[1]

    def _take_due_pose(self) -> None:
        """A sketch drag's end: the pose its run fitted meanwhile taken now (`_take_pose`)."""
        due, self._pose_due = self._pose_due, None
        if due is not None:
            self._take_pose(*due)

    def _swap(self, leaf: Leaf, taken: Any) -> None:
        """Each snapshot whose leaf is `leaf` replaced by `taken(snapshot)` (one new State per
        snapshot: the history's steps share them)."""
        new: dict[int, State] = {}

        def swapped(state: State) -> State:
            if state.leaf is not leaf:
                return state
            if id(state) not in new:
                new[id(state)] = taken(state)
            return new[id(state)]

        self.state = swapped(self.state)
        self._edit_base = self._edit_base and swapped(self._edit_base)
        self._param_base = self._param_base and swapped(self._param_base)
        self._bend_base = self._bend_base and swapped(self._bend_base)
        h = self.history
        h.steps = [Step(s.text, swapped(s.before), swapped(s.after)) for s in h.steps]
        h.changed.emit()
