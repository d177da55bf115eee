"""How the window shows what its session and worker report: a state changed, a result to draw
(a turn later), a failure, the stage running, the timings and notes on the status line, and the
measurements once they are in. A mixin of MainWindow (main_window.py), which owns the widgets
these draw on (viewport, status line, panels, editor) and connects the reports in
`connect_reports`.
"""

from __future__ import annotations

import time
from functools import partial

from PySide6.QtCore import QTimer

from leafstudio.core.kernels import compiling_notice
from leafstudio.gui.model.measurements import measurement_rows
from leafstudio.gui.model.session import Framing, State
from leafstudio.gui.model.status_line import StatusLine
from leafstudio.gui.model.textures import coloring_for
from leafstudio.gui.model.view_aids import k_label
from leafstudio.gui.qt.turns import later
from leafstudio.gui.qt.worker import PIPELINE, Outcome

STAGE_LABEL_MS = 250  # the running stage is shown at most this often (each repaint costs time)


class Reports:
    """The window's answers to the session's and the worker's reports (MainWindow's mixin)."""

    def connect_reports(self) -> None:
        """Listen to the worker's reports; the stage label's timer; no result due yet."""
        self.worker.stage_started.connect(self._on_stage)
        self.worker.yielded.connect(self._on_yielded)
        self.worker.done.connect(self._on_measured)
        self.worker.failed.connect(self._on_pipeline_failed)
        self._result_due: tuple[Outcome, Framing | None] | None = None  # drawn next turn
        self._stage_timer = QTimer(self)
        self._stage_timer.setSingleShot(True)
        self._stage_timer.setInterval(STAGE_LABEL_MS)
        self._stage_timer.timeout.connect(self._show_stage)
        self._stage = ""

    # --- session reports -----------------------------------------------------------------------
    def _on_state(self, state: State, reason: str) -> None:
        if reason in ("document", "undo", "fallback"):
            self.editor.drop_edit()  # a drag or key run under way: its step would mix documents
            self.panel.set_params(state.params)
        if reason == "document":  # the Leaf look, but colour by height for a scan
            is_scan = state.scan is not None
            current = self.viewport.mesh_coloring
            coloring, automatic = coloring_for(is_scan, current, self._coloring_automatic)
            if coloring != current:  # the old mesh's new actor: a turn of its own (turns.py)
                later(self, partial(self._set_coloring, coloring, automatic))
            else:
                self._coloring_automatic = automatic
        self.editor.show_outline_note(self.session.outline_note)  # a loaded leaf redrawn
        if state.scan is not self._scan_shown:  # after the recolouring above: its new actor's
            self._scan_shown = state.scan  # render sets up its shaders, then the points' (turns.py)
            pieces = state.scan.pieces if state.scan is not None else []
            self.layers.set_available("scan", state.scan is not None)
            later(self, partial(self.viewport.set_layer, "scan", pieces))
        self._update_title()

    def _on_cleared(self) -> None:
        self._result_due = None
        self.viewport.clear()
        if (scan := self.session.state.scan) is not None:
            self.viewport.set_layer("scan", scan.pieces)
        self.measurements_panel.clear()
        self.status_text.setStyleSheet("")
        self.status_text.setText(self.session.message)

    def _on_result(self, outcome: Outcome, framing: Framing | None) -> None:
        """Drawn a turn after the session's work on it (a new leaf's derived sketch): two short
        pauses, not one of 32 ms (a 2M-point scan); a newer result then keeps a reset framing."""
        due = self._result_due
        if due is None:
            later(self, self._show_result)
        elif due[1] is not None:  # not drawn yet: a new document's reset, or a refit
            reset = due[1].reset or (framing is not None and framing.reset)
            framing = Framing((framing or due[1]).bounds, reset)
        self._result_due = (outcome, framing)

    def _show_result(self) -> None:
        if self._result_due is None:  # cleared meanwhile (a new sketch)
            return
        (outcome, framing), self._result_due = self._result_due, None
        start, side = time.perf_counter(), self.session.side
        frame = self.session.view_frame() or outcome.result.frame
        how = None if framing is None else ("reset" if framing.reset else "refit")
        bounds = framing.bounds if framing is not None else None
        if how == "reset" and self.viewport.texture_key not in (None, side.texture_key):
            self.viewport.set_texture(None, None, draw=False)  # another leaf's image
        self.viewport.show_layers(outcome.layers, frame, bounds, how)
        self.layers.set_available("blade", bool(outcome.layers.get("blade")))  # a bent leaf's
        self.follow_blade()  # laid flat under the layers drawn there (main_window.py)
        outcome.timings["draw"] = time.perf_counter() - start
        self._stage_timer.stop()
        self._show_timings(outcome)
        self.editor.view.set_crossings(self.session.crossings)
        self.result_shown.emit(outcome)

    def _on_session_failed(self, message: str, fell_back: bool) -> None:
        """A failed reconstruction: said in the status, and over the view while the leaf it
        concerns is the document; a refused file (fell_back) in a box instead, the good leaf
        back on screen without another file's message over it."""
        self.status_text.setStyleSheet("color: #b00020")
        refused = f"{self.opened_name}: " if fell_back and self.opened_name else ""
        kept = " (the previous leaf is kept)" if fell_back else ""
        self.status_text.setText(f"Failed: {refused}{message}{kept}")
        self.viewport.set_message("" if fell_back else message)
        self.editor.view.set_crossings(self.session.crossings)
        if fell_back:
            self.show_error("Cannot reconstruct this leaf", message)
        self.failure_shown.emit(message)

    # --- worker reports ------------------------------------------------------------------------
    def _on_stage(self, kind: str, request_id: int, stage: str) -> None:
        if kind == PIPELINE and request_id == self.session.last_id:
            self._stage = stage
            if not self._stage_timer.isActive():
                self._stage_timer.start()

    def _show_stage(self) -> None:
        if not self.worker.is_idle(PIPELINE):
            self.status_text.setStyleSheet("")
            notice = compiling_notice(self._stage)  # the first run, in worker processes
            self.status_text.setText(notice or f"Running: {self._stage}…")

    def _on_yielded(self, kind: str, job_id: int, value: object) -> None:
        if kind == PIPELINE and not self.session.accept_drawable(value):
            self._on_rendered()  # not shown: no render to wait for

    def _on_rendered(self) -> None:
        """The shown result is on screen: the worker may measure it (Worker.measure_after_drawn);
        while a slider is held, not before it is let go (measuring takes the pipeline's lane
        for ~0.1 s at grid 512, which the drag's next value would wait for)."""
        if not self.panel.is_dragging():
            self.session.drawn()

    def _on_measured(self, kind: str, job_id: int, seconds: object) -> None:
        """The pipeline measured a result (side jobs answer through their handles)."""
        if kind != PIPELINE or not self.session.accept_measured(job_id):
            return
        self._stage_timer.stop()
        if compiling_notice(self._stage) is not None and self.session.result is not None:
            self._stage = ""  # measuring compiled its kernels first: the result's line again
            self._show_timings(self.session.shown.outcome)
        if self.session.result is not None:
            if not self.session.message:  # not after a failure's message (Worker._failed)
                self.status_text.extend(f" · measured in {1000 * seconds:.0f} ms")
            self._show_measurements()

    def _on_pipeline_failed(self, kind: str, job_id: int, exc: BaseException) -> None:
        if kind == PIPELINE:
            self.session.accept_failure(job_id, exc)

    def _show_timings(self, outcome: Outcome) -> None:
        ms = [f"{name} {1000 * t:.0f} ms" for name, t in outcome.timings.items()]
        total = sum(outcome.timings.values())
        result = outcome.result
        request, session = outcome.request.id, self.session
        warned = (*result.warnings, *session.side.warnings_of(request))
        line = StatusLine(  # short enough for a projector; each stage's time in the tip
            # the K used, as the view's corner says it: a flat blade fits none, whatever K was
            # asked (the line said "K=3" beside the corner's "K unused (flat blade)": closing32)
            f"{k_label(result)}, grid {result.params.grid}: shown in {1000 * total:.0f} ms",
            # the edit's note first: it was the user's; each whole in the tip (status_line.py)
            tuple(dict.fromkeys((*session.notes_of(request), *warned))),
            " · ".join(ms) + " (stages not listed came from the cache)",
        )
        self.status_text.setStyleSheet("")
        self.status_text.show_line(line)

    def _on_outline_replaced(self, message: str) -> None:
        """A loaded leaf's first sketch edit replaced its own outline and veins: said on the
        status line now (and with the edit's result, `Session.notes_of`), and as a note over
        the sketch while it draws the leaf (`_on_state`)."""
        self.status_text.setStyleSheet("color: #8a5a00")
        self.status_text.setText(message)
        self.editor.show_outline_note(self.session.outline_note)

    def _show_measurements(self) -> None:
        """Fill the panel once the shown result is measured; with a scan open, its distances
        follow (measurements_shown fires when they are in)."""
        result, shown = self.session.result, self.session.shown
        if result is None or shown.measured_id != self.session.shown_id:
            return
        if not self.docks["Measurements"].isVisible():  # filled when shown: no cost while hidden
            self._measurements_due = True
            self.measurements_shown.emit()  # nothing on screen waits for it
            return
        self._measurements_due = False
        sections = measurement_rows(result)
        fidelity = shown.fidelity
        scan = self.session.state.scan
        waiting = scan is not None and (fidelity is None or fidelity[0] != shown.measured_id)
        if waiting:  # the scan's sections first: with a scan open, they are what matters
            sections.insert(0, ("Scan → mesh distance", [("Computing…", "")]))
        elif fidelity is not None:
            sections[:0] = fidelity[1]
        self.measurements_panel.show_sections(sections)
        if not waiting:
            self.measurements_shown.emit()
