"""Runs the pipeline on one background thread; the newest request wins.

The worker thread owns the Pipeline of the current leaf, so that a parameter change reuses the
stages it does not affect (moving K reruns only gmm, surface and mesh). A request that arrives
while another is waiting replaces it; an *interrupting* request also stops the running one at its
next stage boundary (a slider storm), while a *live* request lets it finish so that the view keeps
moving during a drag. Results, stage names and failures reach the main thread by queued signals;
the datasets to draw are built here too (see layers.py), leaving only rendering to the main thread.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

from PySide6.QtCore import QObject, Signal

from leafstudio.core.pipeline import Cancelled, Pipeline, Result
from leafstudio.errors import LeafError
from leafstudio.gui.layers import Piece, build_layers
from leafstudio.model import Leaf, Params


@dataclass(frozen=True)
class Request:
    """One run to do: which leaf, with which settings."""

    id: int
    leaf: Leaf
    params: Params
    interrupt: bool


@dataclass
class Outcome:
    """A finished run: the Result, what to draw, and the time spent in each step (seconds)."""

    request: Request
    result: Result
    layers: dict[str, list[Piece]]
    timings: dict[str, float] = field(default_factory=dict)
    thread: int = 0


class PipelineWorker(QObject):
    """Accepts requests from the main thread and reports on them by signal.

    Signals
    -------
    stage_started(int, str)
        Request id and the stage about to run.
    finished(object)
        An Outcome.
    measured(int, float)
        Request id and the seconds spent: the finished Result's metrics are now computed (after
        the mesh is shown, so that they do not delay it).
    failed(int, str)
        Request id and the user-facing message.
    """

    stage_started = Signal(int, str)
    finished = Signal(object)
    measured = Signal(int, float)
    failed = Signal(int, str)

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._wake = threading.Condition()
        self._pending: Request | None = None
        self._quit = False
        self._busy = False
        self._last_id = 0
        self._pipeline: Pipeline | None = None
        # a daemon thread: quitting during a long stage must not wait for it (nor abort, as a
        # running QThread would when destroyed)
        self._thread = threading.Thread(target=self.loop, name="leafstudio-pipeline", daemon=True)
        self._thread.start()

    def submit(self, leaf: Leaf, params: Params, interrupt: bool = True) -> int:
        """Queue a run (replacing any waiting one) and return its request id."""
        with self._wake:
            self._last_id += 1
            self._pending = Request(self._last_id, leaf, params, interrupt)
            self._wake.notify()
            return self._last_id

    @property
    def last_id(self) -> int:
        """Id of the newest request."""
        return self._last_id

    def is_idle(self) -> bool:
        """True when nothing is running or waiting."""
        with self._wake:
            return self._pending is None and not self._busy

    def shutdown(self, wait_ms: int = 10_000) -> None:
        """Stop the thread at the next stage boundary and wait for it."""
        with self._wake:
            self._quit = True
            self._pending = None
            self._wake.notify()
        self._thread.join(wait_ms / 1000)

    # --- on the worker thread ------------------------------------------------------------------
    def _should_stop(self) -> bool:
        pending = self._pending
        return self._quit or (pending is not None and pending.interrupt)

    def _next(self) -> Request | None:
        with self._wake:
            self._busy = False
            while self._pending is None and not self._quit:
                self._wake.wait()
            if self._quit:
                return None
            request, self._pending = self._pending, None
            self._busy = True
            return request

    def _run(self, request: Request) -> Outcome:
        if self._pipeline is None or self._pipeline.leaf is not request.leaf:
            self._pipeline = Pipeline(request.leaf)
        result = self._pipeline.run(
            request.params,
            on_stage=lambda name: self.stage_started.emit(request.id, name),
            should_stop=self._should_stop,
        )
        timings = dict(result.timings)
        start = time.perf_counter()
        layers = build_layers(result)
        timings["layers"] = time.perf_counter() - start
        return Outcome(request, result, layers, timings, threading.get_ident())

    def loop(self) -> None:
        """The worker thread's body: take the newest request, run it, report, repeat."""
        while (request := self._next()) is not None:
            try:
                outcome = self._run(request)
            except Cancelled:
                continue
            except LeafError as exc:
                self.failed.emit(request.id, str(exc))
                continue
            except Exception as exc:  # shown in the window; the app keeps running
                self.failed.emit(request.id, f"internal error: {type(exc).__name__}: {exc}")
                continue
            if self._should_stop():  # a newer interrupting request makes this stale
                continue
            self.finished.emit(outcome)
            if self._should_stop():  # measure only what stays on screen
                continue
            start = time.perf_counter()
            try:
                _ = outcome.result.metrics  # here, not on the main thread when the panel reads it
            except Exception as exc:  # the mesh is shown; say why its measurements are not
                self.failed.emit(request.id, f"measurements failed: {type(exc).__name__}: {exc}")
                continue
            self.measured.emit(request.id, time.perf_counter() - start)
