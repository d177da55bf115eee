"""How a Session takes the worker's reports: a result to draw (unless a newer one was shown),
its measurements and the scan's distances to it, and a failure, which keeps the last good result
or brings back the document from before a newly opened one (its history with it). A mixin of
Session (session.py), which owns the state these read and set. No Qt.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from leafstudio.gui.model.framing import Framing, blade_bounds
from leafstudio.gui.model.history import State, Step
from leafstudio.gui.model.jobs import describe
from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.model import Leaf


@dataclass
class Shown:
    """What the session last accepted from the worker."""

    outcome: Any = None  # worker.Outcome
    measured_id: int = 0
    fidelity: tuple[int, list] | None = None  # request id, the panel's scan sections


@dataclass
class Fallback:
    """The document from before a newly opened one, brought back if its first run fails."""

    state: State
    steps: list[Step] = field(default_factory=list)
    index: int = 0
    clean: int | None = 0
    request: int = 0
    derived: Sketch | None = None  # the state's sketch derived from its result, if any
    derived_leaf: Leaf | None = None


class WorkerReports:
    """The Session's answers to the worker's reports (its mixin)."""

    def accept_drawable(self, outcome: Any) -> bool:
        """The worker's outcome to draw (accept_result); the worker measures it once it is on
        screen (Outcome.drawn, set by `drawn`), an older one at once: it will never be."""
        if self._drawn_due is not None:
            self._drawn_due.set()  # a newer result replaces it before its render
        self._drawn_due = outcome.drawn
        return self.accept_result(outcome)

    def drawn(self) -> None:
        """The shown result is on screen (or will not be): it may be measured."""
        if self._drawn_due is not None:
            self._drawn_due.set()
            self._drawn_due = None

    def accept_result(self, outcome: Any) -> bool:
        """A finished reconstruction: shown unless a newer one was shown already."""
        request_id = outcome.request.id
        if request_id < self.shown_id or request_id <= self._ignored_upto:
            return False
        self.shown = Shown(outcome, 0, None)
        if self._fallback is not None and request_id >= self._fallback.request:
            self._fallback = None
        result = outcome.result
        serial, reason, _ = self._requested.get(request_id, (self.state.serial, "document", None))
        self._take_pose(request_id, outcome)  # a pose its run fitted: the document's
        if self.derives(result.leaf):  # derived by the worker, if it knew (Worker.derives)
            self.derived = getattr(outcome, "sketch", None) or Sketch.from_result(result)
            self._derived_leaf = result.leaf
            self.sketch_shown.emit(self.derived, True)
        frame = self.view_frame() or result.frame
        bounds = blade_bounds(result.triangle_mesh.points, frame)
        framing = None
        if self._framed is None or self._framed[0] != serial:
            framing = Framing(bounds, reset=True)
        elif reason in ("edit", "undo") and not self._framed[1].contains(bounds):
            framing = Framing(bounds.union(self._framed[1]), reset=False)
        if framing is not None:
            self._framed = (serial, framing.bounds)
        self.message = ""
        if framing is not None and framing.reset:
            self.side.new_leaf(result)  # another leaf's image: the view drops it
        self.result_shown.emit(outcome, framing)
        self.side.result_shown(outcome)
        self.open_settled(request_id)
        return True

    def accept_measured(self, request_id: int) -> bool:
        """The shown result's metrics are computed (on the worker)."""
        if request_id != self.shown_id:
            return False
        self.shown.measured_id = request_id
        return True

    def accept_fidelity(self, request_id: int, sections: list) -> bool:
        """The scan's distances to result `request_id`."""
        if request_id != self.shown_id or self.state.scan is None:
            return False
        self.shown.fidelity = (request_id, sections)
        return True

    def accept_failure(self, request_id: int, exc: BaseException) -> bool:
        """A failed reconstruction: the last good result stays; a newly opened document that
        fails brings the previous one back. True when the failure concerns what is shown."""
        if request_id < self.shown_id or request_id < self.last_id:
            return False
        if request_id <= self._ignored_upto:
            return False
        self.message = describe(exc)
        fallback = self._fallback
        fell_back = fallback is not None and request_id >= fallback.request
        self.failed.emit(self.message, fell_back and self._restore_fallback())
        self.open_settled(request_id)
        return True

    def _restore_fallback(self) -> bool:
        """Bring back the document from before a newly opened one (its first run failed or was
        cancelled), with its history; False when there is none to bring back."""
        fallback = self._fallback
        if fallback is None or self.result is None:
            return False
        self._fallback = None
        self._drop_edit()  # an edit begun on the failed document
        self.state = fallback.state
        self.derived, self._derived_leaf = fallback.derived, fallback.derived_leaf
        h = self.history
        h.steps, h.index, h.clean_index = fallback.steps, fallback.index, fallback.clean
        h.changed.emit()
        self.state_changed.emit(self.state, "fallback")
        self.sketch_shown.emit(self.editable_sketch() or Sketch(), True)
        return True
