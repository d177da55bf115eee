"""The app's state without Qt: the document, its parameters, results, the pending request and
the undo history. The window displays a Session and forwards the user's edits to it; the
worker's reports come back to it (as napari's ViewerModel and its `_qt` views).

For other features (the forms gallery, imports): `Session.new_document(leaf, sketch=None,
title=...)` replaces the document as ONE undo step (Ctrl+Z brings the previous one back);
`Session.open_document(...)` does the same for a file, clearing the history instead.

Files open here too (`open_path`: read on the worker's side lane through workflows.open_file,
the path the command line and batch take), as do demos and new sketches; the side jobs of the
shown result (the scan's distances, the Poisson surface, the texture) live in `session.side`
(side.py); how the worker's reports are taken is reports.py's.

Every user story can be played on a Session in plain pytest: give it a `submit` callable that
records or runs requests, then hand it `accept_result` / `accept_failure` as the worker would;
side jobs and file reading run at once (jobs.run_now) unless a `run` is given.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from leafstudio.core.plane import Frame
from leafstudio.core.prepare.polygon import ring_crossings
from leafstudio.core.unfolded import as_given
from leafstudio.gui.model.bending import Bending, keeps_refusal
from leafstudio.gui.model.framing import BladeBounds, Framing
from leafstudio.gui.model.history import Event, History, State, Step
from leafstudio.gui.model.jobs import Job, Run, describe, run_now
from leafstudio.gui.model.opening import FileOpening, missing_photo_message
from leafstudio.gui.model.pose_fits import PoseFits
from leafstudio.gui.model.reports import Fallback, Shown, WorkerReports
from leafstudio.gui.model.side import SideJobs
from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.model import PARAMS, Leaf, Params
from leafstudio.sources.demos import PAPER_K, demo

__all__ = ["Event", "Framing", "History", "Session", "State", "Step", "describe"]

log = logging.getLogger("leafstudio.gui")


def _param_text(before: Params, after: Params) -> str:
    """The undo step's name: the parameters changed, as their messages name them."""
    changed = [p.what for n, p in PARAMS.items() if getattr(before, n) != getattr(after, n)]
    return "Change " + ", ".join(changed)


def _whose(state: State) -> str:
    """Whose outline a loaded document's derived sketch approximates."""
    return "the scan's" if state.scan is not None else "the opened leaf's"


def replaced_text(before: State, sketch: Sketch) -> str:
    """What the first edit of `before`'s derived sketch did: the loaded leaf's (a scan's, a
    file's) outline and veins replaced by the sketch's curves, and how to get them back."""
    return (  # short: the status line shows ~170 characters in a 1500-pixel window
        f"Editing replaced {_whose(before)} outline and veins by the sketch's curves "
        f"({len(sketch.boundary)} outline points); Undo (Ctrl+Z) brings them back."
    )


class Session(FileOpening, Bending, PoseFits, WorkerReports):
    """The document, parameters, results, pending request and history.

    Parameters
    ----------
    submit : callable(leaf, params, interrupt) -> int
        Queues a reconstruction and returns its request id (the window passes the worker's).
    params : Params
        The parameters of the first document.
    run : jobs.Run, optional
        Starts a side job, `run(kind, function, *args) -> Job` (the window passes the worker's
        `start`); jobs.run_now, at once, by default.
    cancel : callable(int), optional
        Stops a reconstruction `submit` queued, by its request id (the window passes the
        worker's `cancel`): Cancel during an opened file's first run.

    Events
    ------
    state_changed(State, str)
        The document or parameters changed; the reason: "document", "edit", "params", "undo",
        "fitted" (a run's pose fitted to its curves taken: pose_fits.py).
    result_shown(outcome, Framing | None)
        A result to display, with how to frame it (None: keep the camera).
    failed(str, bool)
        A message for the user; True when the document fell back to the previous one.
    cleared()
        No leaf to show (a sketch with fewer than 3 boundary points).
    sketch_shown(Sketch, bool)
        The sketch the editor should show, and whether to fit the view to it: sent whenever the
        document's sketch changes, whatever changed it (an edit that came from the editor comes
        back as the very sketch it shows, which the editor ignores).
    sketch_waiting()
        A new document (or an undo to another one) whose sketch is not known yet: a loaded
        leaf's is derived from its first result. The editor must drop the sketch it shows and
        take no edit until sketch_shown: an edit of the old sketch would replace the new leaf.
    crossing(ndarray)
        The sketch's boundary crossings, (c, 2) plane points (empty when it does not cross).
    noticed(str)
        A message for the user that is not a failure (a project's photo is missing).
    outline_replaced(str)
        The first edit of a loaded leaf's derived sketch (a scan's, a file's) replaced the leaf's
        own outline and veins by the sketch's curves: what to tell the user (`replaced_text`);
        `outline_note` says it while the document is drawn by that sketch.
    opening(str, str)
        A file is being read: its path, and what it is read as ("photo", "scan" or "file").
    opened(str)
        A file read became the document (the window adds it to the recent files).
    open_cancelled()
        Opening the file was cancelled (cancel_open): the document stays, or comes back.
    open_progress(float | None, str)
        How far opening the file has come (None: not known) and what it is doing ("reading",
        "reconstructing"...).
    open_ended()
        Opening the file is over: its first result is shown, or it failed or was cancelled.
    open_failed(str, str)
        A file could not be opened: what it was read as, and why; the document stays.
    fitting(str)
        Fit pose again asked the worker to fit the leaf's curves: what to say while it does.
    """

    def __init__(
        self,
        submit: Callable[[Leaf, Params, bool], int] | None = None,
        params: Params | None = None,
        run: Run | None = None,
        cancel: Callable[[int], object] | None = None,
    ) -> None:
        self.submit = submit or (lambda leaf, params, interrupt: 0)
        self.run = run or run_now
        self.cancel_request = cancel or (lambda request_id: None)
        self.state = State(None, None, params or Params())
        self.history = History(moved=self._history_moved)
        self.shown = Shown()
        self.last_id = 0  # the newest request submitted
        self.derived: Sketch | None = None  # a loaded leaf's sketch, made from its first result
        self._derived_leaf: Leaf | None = None
        self.crossings = np.zeros((0, 2))
        self.message = ""
        self.state_changed, self.result_shown, self.failed = Event(), Event(), Event()
        self.cleared, self.sketch_shown, self.crossing = Event(), Event(), Event()
        self.noticed, self.sketch_waiting, self.outline_replaced = Event(), Event(), Event()
        self._replaced: dict[int, str] = {}  # serial -> whose outline its first edit replaced
        self._told: tuple[int, str] = (-1, "")  # the request of the edit that replaced it
        self.opening, self.opened, self.open_failed = Event(), Event(), Event()
        self.open_cancelled, self.open_progress, self.open_ended = Event(), Event(), Event()
        self.fitting = Event()
        self.chosen_texture: Any = None  # a texture picked for the export, shown too
        self._open_due: Job | None = None  # the file being read; another open supersedes it
        self._open_run: int | None = None  # the opened file's first run, until it is shown
        self._ignored_upto = 0  # requests of a cancelled first run: their answers are dropped
        self._drawn_due: threading.Event | None = None  # the outcome being drawn (Outcome.drawn)
        self._serials = 0
        # request id -> serial, reason, the document's leaf it ran (pose_fits.py)
        self._requested: dict[int, tuple[int, str, Leaf | None]] = {}
        self._framed: tuple[int, BladeBounds] | None = None
        self._edit_base: State | None = None
        self._param_base: State | None = None
        self._fallback: Fallback | None = None
        self.side = SideJobs(self)

    # --- reading -------------------------------------------------------------------------------
    @property
    def leaf(self) -> Leaf | None:
        return self.state.leaf

    @property
    def params(self) -> Params:
        return self.state.params

    @property
    def result(self) -> Any:
        """The last good Result shown, or None."""
        return self.shown.outcome.result if self.shown.outcome is not None else None

    @property
    def shown_id(self) -> int:
        return self.shown.outcome.request.id if self.shown.outcome is not None else 0

    def editable_sketch(self) -> Sketch | None:
        """The sketch edits start from: the document's, else the one derived from its result."""
        if self.state.sketch is not None:
            return self.state.sketch
        if self.derived is not None and self.result is not None and self.result.leaf is self.leaf:
            return self.derived
        return None

    def derives(self, leaf: Leaf) -> bool:
        """Whether `leaf`'s result gives the editor its sketch: a loaded leaf's first."""
        fresh = self.derived is None or self._derived_leaf is not leaf
        return self.state.sketch is None and leaf is self.leaf and fresh

    def view_frame(self) -> Frame | None:
        """The plane both views show the leaf on: the sketch's (so the 3D top view and the
        sketch are the same way round), else the shown result's."""
        sketch = self.editable_sketch()
        if sketch is not None and len(sketch.boundary):
            return sketch.frame
        return self.result.frame if self.result is not None else None

    @property
    def outline_note(self) -> str:
        """What to say while the document is a loaded leaf drawn by its edited sketch (its own
        outline and veins replaced at the first edit: `outline_replaced`), "" otherwise; Undo
        back to before that edit brings the leaf's own curves back, and the note goes."""
        if self.state.sketch is None or self.state.serial not in self._replaced:
            return ""
        return (
            f"Drawn by the sketch: {self._replaced[self.state.serial]} outline and veins were "
            "replaced by its curves at its first edit, so the surface may have moved slightly "
            "(undo the edits to bring them back)."
        )

    def notes_of(self, request_id: int) -> list[str]:
        """Notes about result `request_id` said with it on the status line: the edit that
        replaced a loaded leaf's outline, on its result (the line is rewritten when a result is
        drawn, which came a moment after the edit's message)."""
        request, note = self._told
        return [note] if note and request == request_id else []

    def is_modified(self) -> bool:
        """True when there are edits (sketch or parameters) not saved."""
        return not self.history.is_clean()

    # --- documents -----------------------------------------------------------------------------
    def new_document(
        self,
        leaf: Leaf | None,
        sketch: Sketch | None = None,
        title: str = "untitled",
        *,
        params: Params | None = None,
        path: str | None = None,
        scan: Any = None,
        photo: Any = None,
        undoable: bool = True,
        unposed: float | None = None,
    ) -> int:
        """Make a new document current (framed when shown), as one undo step; returns the
        request id (0 when there is nothing to reconstruct). `undoable=False` starts a fresh
        history instead and falls back to the current document if the new one fails. `photo`
        (a LeafPhoto) is the photo the leaf was found in: its texture; `unposed`, a leaf in 3D
        no pose lays flat (State.unposed)."""
        if sketch is not None and leaf is None:
            leaf = sketch.to_leaf()
        self._serials += 1
        before = self._drop_edit()  # the step (or the fallback) starts from before it
        params = params or before.params  # a held slider's value is dropped with its drag
        state = State(leaf, sketch, params, path, title, scan, self._serials, photo, unposed)
        self.chosen_texture = None
        self._fallback = None
        if not undoable and leaf is not None and self.result is not None:
            h, derived = self.history, (self.derived, self._derived_leaf)
            self._fallback = Fallback(before, list(h.steps), h.index, h.clean_index, 0, *derived)
        self.derived = None
        self._apply(state, "document")
        if undoable:
            self.history.push(Step(f"New leaf: {title}", before, state))
        else:
            self.history.clear()
        request = self.last_id if self.leaf is not None else 0
        if self._fallback is not None:
            self._fallback.request = request
        if photo is not None and not photo.exists():
            self.noticed.emit(missing_photo_message(photo))
        return request

    def texture(self) -> Any:
        """What the leaf's texture is, in the view and in an export: an image picked for the
        export, else the photo the leaf came from (while it is there), else "auto" (generated
        from the leaf). Each as assets.export's `texture` option takes it."""
        if self.chosen_texture is not None:
            return self.chosen_texture
        photo = self.state.photo
        if photo is not None and photo.exists():
            return photo.texture()
        return "auto"

    def open_document(self, leaf: Leaf | None, sketch: Sketch | None, title: str, **kw: Any) -> int:
        """A file, demo or scan: a new document with a fresh history; if its first result
        fails, the previous document comes back."""
        return self.new_document(leaf, sketch, title, undoable=False, **kw)

    def new_sketch(self) -> int:
        """An empty sketch to draw in (a file being read is cancelled)."""
        self.cancel_open()
        return self.open_document(None, Sketch(), "new sketch", params=self.params)

    def open_demo(self, name: str) -> int:
        """A built-in leaf with the paper's K (a file being read is cancelled)."""
        self.cancel_open()
        params = self.params.with_(k=PAPER_K.get(name, self.params.k))
        return self.open_document(demo(name), None, f"{name} demo", params=params)

    def choose_texture(self, texture: Any) -> None:
        """A texture picked for an export (an assets.export `texture` option): the view shows
        it too, until another document opens."""
        self.chosen_texture = texture
        self.side.update_texture()

    def saved(self, path: str) -> None:
        """The document was written to `path`: it is now its file and unmodified."""
        self.state = replace(self.state, path=path)
        self.history.set_clean()
        self.state_changed.emit(self.state, "saved")

    # --- edits ---------------------------------------------------------------------------------
    def preview_sketch(self, sketch: Sketch) -> None:
        """A sketch during a drag: shown live, not yet an undo step."""
        if self._edit_base is None:
            self._edit_base = self.state
        state = replace(self.state, leaf=self.sketch_leaf(sketch), sketch=sketch)
        self._apply(state, "edit", live=True)

    def commit_sketch(self, sketch: Sketch, text: str, before: Sketch | None = None) -> None:
        """A finished sketch edit, from the editor's sketch `before` (when it says): one undo
        step from before the edit (or drag) began."""
        base = self._edit_base or self.state
        self._edit_base = None
        if self.state.sketch is not sketch:  # a drag's last preview is requested already
            leaf = self.sketch_leaf(sketch, before)
            self._apply(replace(self.state, leaf=leaf, sketch=sketch), "edit")
        self.history.push(Step(text, base, self.state))
        self._take_due_pose()  # a pose its drag's run fitted (pose_fits.py)
        if base.sketch is None and base.leaf is not None and self.state.sketch is not None:
            # a loaded leaf's first edit: the leaf is the sketch's from now on, not its own
            # (soybean pot1_1 at grid 128: its outline through 3,000 points became a curve
            # through 85, the area 1.4% less, the mesh moved up to 0.93 mm), said once and kept
            # as a note
            note = replaced_text(base, self.state.sketch)
            self._replaced[self.state.serial] = _whose(base)
            self._told = (self.last_id, note)
            self.outline_replaced.emit(note)

    def set_symmetric(self, on: bool) -> None:
        """Mirror editing on or off. It is a property of the drawing, saved with its sketch
        (Sketch.symmetric), so turning it is an undo step and marks the document modified, as
        any change to what Save writes; the leaf, and so the 3D view, stay as they are.

        A loaded leaf not yet edited has no sketch of its own (the editor shows one derived from
        its result): making that the document would replace the leaf by its approximation, so
        the flag rides on the derived sketch and enters the document with the first edit."""
        sketch = self.editable_sketch()
        if sketch is None or sketch.symmetric == on:
            return
        sketch = replace(sketch, symmetric=on)
        if self.state.sketch is None:
            self.derived = sketch
            self.sketch_shown.emit(sketch, False)
            return
        before = self.state
        self._apply(replace(self.state, sketch=sketch), "mirror")
        self.history.push(Step("Mirror on" if on else "Mirror off", before, self.state))

    def set_params(self, params: Params, final: bool = True) -> None:
        """New parameters: `final=False` while a slider is held (shown, not an undo step);
        `final=True` on release or any other change: one undo step from before the drag."""
        if self._param_base is None:
            self._param_base = self.state
        base = self._param_base
        if params != self.params:
            self._apply(replace(self.state, params=params), "params")
        if final:
            self._param_base = None
            if base.params != self.params:
                self.history.push(Step(_param_text(base.params, self.params), base, self.state))

    def undo(self) -> None:
        self.history.undo()

    def redo(self) -> None:
        self.history.redo()

    def _drop_edit(self) -> State:
        """Drop the edit under way (a drag, a held slider, a run of key presses), if any, and
        return the state from before it began: the one the history's last step led to.

        Undo, redo and a new document drop it rather than commit it: committing would push a
        step and so throw away the redo steps (Redo would then redo nothing), and the session
        cannot name the unfinished gesture. Its base must not outlive them either, or the next
        edit's step would go from a state from before the undo and bring back what was undone.
        The widgets drop their part when the new state's sketch reaches them."""
        base = self._edit_base or self._param_base or self.state
        self._edit_base = self._param_base = None
        return base

    def _history_moved(self, state: State) -> None:
        """Undo or redo made `state` current: an edit under way is dropped (see _drop_edit)."""
        self._drop_edit()
        self._apply(state, "undo")

    # --- requests ------------------------------------------------------------------------------
    def _crossing_of(self, sketch: Sketch | None) -> np.ndarray | None:
        if sketch is None:
            return None
        found = ring_crossings(sketch.boundary_curve())
        return found if len(found) else None

    def _apply(self, state: State, reason: str, live: bool = False) -> None:
        old = self.state
        self.state = state
        self.state_changed.emit(state, reason)
        if reason in ("document", "undo"):
            shown = state.sketch
            if state.sketch is None and self.derived is not None and old.serial == state.serial:
                shown = self.derived  # undo back to the loaded leaf: its derived sketch
            if shown is not None:
                self.sketch_shown.emit(shown, reason == "document")
            else:  # a loaded leaf: its sketch comes with its first result
                self.sketch_waiting.emit()
        elif state.sketch is not None and state.sketch is not old.sketch:
            # any other change of the document's sketch (Grow veins, Mirror, the editor's own
            # edit, which it ignores): the editor must show it, or its next edit would start
            # from the sketch it still shows and throw this one away
            self.sketch_shown.emit(state.sketch, False)
        if state.leaf is old.leaf and state.params == old.params and reason != "document":
            return
        self._request(interrupt=not live, reason=reason)

    def _request(self, interrupt: bool = True, reason: str = "document") -> int:
        crossing = self._crossing_of(self.state.sketch)
        self.crossings = crossing if crossing is not None else np.zeros((0, 2))
        self.crossing.emit(self.crossings)
        if crossing is not None:
            x, y = crossing[0]
            self.message = (
                f"The boundary crosses itself near ({x:.3g}, {y:.3g}); the 3D view keeps the "
                "last leaf without a crossing."
            )
            self.failed.emit(self.message, False)
            return 0
        if self.leaf is None:
            self.message = "Add at least 3 boundary points to see the leaf."
            self.cleared.emit()
            return 0
        if keeps_refusal(self.state):  # its curves edited since no pose was found for them
            as_given(self.leaf)
        self.last_id = self.submit(self.leaf, self.params, interrupt)
        self._requested[self.last_id] = (self.state.serial, reason, self.leaf)
        for old in [i for i in self._requested if i < self.last_id - 64]:
            del self._requested[old]
        return self.last_id
