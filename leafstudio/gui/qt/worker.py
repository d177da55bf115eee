"""Background work, newest request wins: the pipeline and the side tasks, one implementation.

`Worker` runs jobs on a few threads ("lanes": the pipeline's, and one for side tasks such as
reading a scan, its distances to a mesh, the Poisson surface, so that these never hold up a
reconstruction). Each job has a kind; a new job replaces a waiting one of its kind, and an
*interrupting* job also stops the running one of its kind at its next check (a slider storm),
while a *live* one lets it finish (the view keeps moving during a drag).

A job is a callable taking a `Context` (should_stop, stage) and its arguments. A generator job
reports each value it yields (`yielded`) before it goes on: the pipeline yields the Outcome to
draw, then measures it, in steps (Result.measure): a newer request, interrupting or not, stops
the measuring at its next step (a few tens of ms at most), so that measuring never holds it up;
the steps done are kept on the Result, and when that newer request fails the lane goes back to
measure what is shown. Failures are reported as exception objects and logged with their
traceback. The pipeline's Pipeline object lives on its lane, so a parameter change reuses the
stages it does not affect. Qt signals carry the reports to the main thread; a side job started
with `start` also answers through its own handle (gui/model/jobs.py), on the main thread.
"""

from __future__ import annotations

import contextlib
import inspect
import logging
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

from PySide6.QtCore import QObject, Signal

from leafstudio.core.kernels import MEASURE, compile_kernels
from leafstudio.core.pipeline import Cancelled, Pipeline, Result
from leafstudio.core.store import StageStore
from leafstudio.errors import LeafError
from leafstudio.gui.model.jobs import Job, running
from leafstudio.gui.model.layers import Piece, build_layers
from leafstudio.gui.model.pose_fits import pose_fitted
from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.model import Leaf, Params

log = logging.getLogger("leafstudio.gui")

PIPELINE = "pipeline"
SHUTDOWN_WAIT_MS = 100  # the longest closing waits for a running job to stop (see shutdown)
# each lane's thread runs this much nicer than the window's main thread (issue 24): on a 2-core
# host a reconstruction or a scan's distances took the cores a render needs (the main thread and
# software OpenGL's threads), stretching a 45 ms render to 100-150 ms while K changed on a
# 2M-point scan; the processes a lane starts inherit it (the reading child, compile workers).
# 5, not 10: beside a user's other work a lane 10 nicer got a tenth of a core (the demo's window
# and first mesh beside two busy processes: 8.9-11.3 s at 10, 5.9-6.4 s at 5, 4.6-4.9 s at 0,
# 3.0 s on a quiet host), while the window's stalls stay as short (bench_gui --big, quiet host,
# longest stall of two runs: 31 ms at 10, 27 ms at 5, 44 ms at 0)
LANE_NICENESS = 5
LANES = {
    PIPELINE: "pipeline",
    "open": "side",
    "fidelity": "side",
    "poisson": "side",
    "texture": "side",
    "export": "export",  # files written off the main thread (exports.py), never behind a scan
    "thumbnails": "gallery",  # the Forms gallery's veins after a first result, never behind a file
    "form": "forms",  # a chosen form's blade (form_sketch.grow_blade), never behind the gallery
}


@dataclass(frozen=True)
class Request:
    """One run to do: which leaf, with which settings."""

    id: int
    leaf: Leaf
    params: Params
    interrupt: bool
    derive: bool = False  # derive the sketch of its leaf (Worker.derives): a loaded leaf's


@dataclass
class Outcome:
    """A finished run: the Result, what to draw, and the time spent in each step (seconds)."""

    request: Request
    result: Result
    layers: dict[str, list[Piece]]
    timings: dict[str, float] = field(default_factory=dict)
    thread: int = 0
    sketch: Sketch | None = None  # the leaf's derived sketch, if the request asked for it
    # set by the window once the outcome is on screen (or will not be): measuring waits for it
    drawn: threading.Event = field(default_factory=threading.Event, repr=False)


@dataclass
class _Job:
    id: int
    kind: str
    job: Callable[..., Any]
    args: tuple
    interrupt: bool


class Context:
    """What a running job may ask: whether to stop, and to report the stage it starts."""

    def __init__(self, worker: Worker, job: _Job) -> None:
        self._worker, self._job = worker, job

    def should_stop(self) -> bool:
        return self._worker._superseded(self._job) or self._job.id in self._worker._cancelled

    def stage(self, name: str) -> None:
        if not self._worker._quit:
            self._worker.stage_started.emit(self._job.kind, self._job.id, name)

    def progress(self, fraction: float | None, what: str) -> None:
        """How far the job has come (_shared/progress.report on its thread)."""
        if not self._worker._quit:
            self._worker.progressed.emit(self._job.kind, self._job.id, fraction, what)

    def newer_waiting(self) -> bool:
        """True when a newer job of this kind waits, interrupting or not."""
        return self._job.kind in self._worker._pending


class Worker(QObject):
    """Runs submitted jobs, one lane per thread, and reports by queued signal.

    Signals
    -------
    stage_started(str, int, str)
        Kind, job id and the stage about to run.
    yielded(str, int, object)
        Kind, job id and a value a generator job yielded.
    done(str, int, object)
        Kind, job id and the job's return value.
    failed(str, int, object)
        Kind, job id and the exception (already logged with its traceback).
    progressed(str, int, object, str)
        Kind, job id, the fraction done (or None) and what the job is doing.
    """

    stage_started = Signal(str, int, str)
    yielded = Signal(str, int, object)
    done = Signal(str, int, object)
    failed = Signal(str, int, object)
    progressed = Signal(str, int, object, str)

    def __init__(self, parent: QObject | None = None, lanes: dict[str, str] | None = None) -> None:
        super().__init__(parent)
        self.lanes = dict(lanes or LANES)
        self._wake = threading.Condition()
        self._pending: dict[str, _Job] = {}
        self._cancelled: set[int] = set()  # ids of running jobs asked to stop (Worker.cancel)
        self._running: dict[str, _Job | None] = {lane: None for lane in set(self.lanes.values())}
        self._last_id = 0
        self._handles: dict[int, Job] = {}  # started jobs not yet answered (main thread only)
        self.done.connect(self._answer_done)
        self.failed.connect(self._answer_failed)
        self.progressed.connect(self._answer_progress)
        self._quit = False
        self._pipeline: Pipeline | None = None  # touched on the pipeline lane only
        # every leaf's pipeline keeps its stages here, keyed on the leaf's coordinates: the same
        # leaf opened again (a file or demo reopened, a form chosen again) reruns nothing
        self._store = StageStore()
        self._shown: Outcome | None = None  # the last outcome yielded (pipeline lane only)
        # measure a result only once the window has drawn it (Outcome.drawn), so that measuring
        # never competes with the render for the host's cores (software OpenGL renders on them)
        self.measure_after_drawn = False
        # whether a leaf's first result gives the editor its sketch (Session.derives): derived
        # here with the result (Sketch.from_result: 33 ms of a 2M-point scan's, issue 24)
        self.derives: Callable[[Leaf], bool] = lambda leaf: False
        # daemon threads: quitting during a long stage must not wait for it
        self._threads = [
            threading.Thread(
                target=self._loop, args=(lane,), name=f"leafstudio-{lane}", daemon=True
            )
            for lane in self._running
        ]
        for thread in self._threads:
            thread.start()

    # --- on the main thread --------------------------------------------------------------------
    def submit(
        self, kind: str, job: Callable[..., Any], *args: Any, interrupt: bool = False
    ) -> int:
        """Queue `job(context, *args)`, replacing a waiting job of its kind; returns its id."""
        with self._wake:
            self._last_id += 1
            self._pending[kind] = _Job(self._last_id, kind, job, args, interrupt)
            self._wake.notify_all()
            return self._last_id

    def start(self, kind: str, function: Callable[..., Any], *args: Any) -> Job:
        """Queue `function(*args)` as a side job (the Session's `run`, jobs.Run), replacing a
        waiting job of its kind; its handle reports how it ended, on the main thread."""
        job = Job()
        with self._wake:
            replaced = self._pending.get(kind)  # never runs: no answer
            job.id = self.submit(kind, _plain(function), *args)
        if replaced is not None:
            self._handles.pop(replaced.id, None)
        self._handles[job.id] = job
        job.canceller = lambda: self.cancel(job.id)
        return job

    def cancel(self, job_id: int) -> None:
        """Cancel job `job_id`: dropped if it waits, asked to stop (Context.should_stop,
        jobs.cancel_point) if it runs; no report either way."""
        self._handles.pop(job_id, None)
        with self._wake:
            for kind, waiting in list(self._pending.items()):
                if waiting.id == job_id:
                    del self._pending[kind]
            if any(job is not None and job.id == job_id for job in self._running.values()):
                self._cancelled.add(job_id)

    def _answer_done(self, _kind: str, job_id: int, value: object) -> None:
        if (job := self._handles.pop(job_id, None)) is not None:
            job.finish(value)

    def _answer_failed(self, _kind: str, job_id: int, exc: BaseException) -> None:
        if (job := self._handles.pop(job_id, None)) is not None:
            job.fail(exc)

    def _answer_progress(self, _kind: str, job_id: int, fraction: object, what: str) -> None:
        if (job := self._handles.get(job_id)) is not None:
            job.progressed.emit(fraction, what)

    def submit_pipeline(self, leaf: Leaf, params: Params, interrupt: bool = True) -> int:
        """Queue a reconstruction (the Session's `submit`)."""
        with self._wake:
            request = Request(self._last_id + 1, leaf, params, interrupt, self.derives(leaf))
            return self.submit(PIPELINE, self._reconstruct, request, interrupt=interrupt)

    @property
    def last_id(self) -> int:
        """Id of the newest job."""
        return self._last_id

    def is_idle(self, lane: str | None = None) -> bool:
        """True when nothing is running or waiting (on `lane`, or anywhere)."""
        with self._wake:
            jobs = [*self._pending.values(), *(j for j in self._running.values() if j)]
            return not any(lane is None or self.lanes[j.kind] == lane for j in jobs)

    def join(self, timeout_s: float) -> bool:
        """After shutdown: wait up to `timeout_s` for the lanes' threads to end (a test's
        teardown, so that no job outlives it); True when they all did."""
        deadline = time.monotonic() + timeout_s
        for thread in self._threads:
            thread.join(max(0.0, deadline - time.monotonic()))
        return not any(thread.is_alive() for thread in self._threads)

    def shutdown(self, wait_ms: int = SHUTDOWN_WAIT_MS) -> None:
        """Drop waiting jobs, ask running ones to stop at their next check, and wait for the
        threads at most `wait_ms`: a job in a long step that cannot check (a compiled kernel, a
        file being read) is left to end with the process (daemon threads, which report nothing
        once shut down), so that closing the window never waits for it."""
        with self._wake:
            self._quit = True
            self._pending.clear()
            self._wake.notify_all()
        deadline = time.monotonic() + wait_ms / 1000
        for thread in self._threads:
            thread.join(max(0.0, deadline - time.monotonic()))

    # --- on the worker threads -----------------------------------------------------------------
    def _superseded(self, job: _Job) -> bool:
        newer = self._pending.get(job.kind)
        return self._quit or (newer is not None and newer.interrupt)

    def _next(self, lane: str) -> _Job | None:
        with self._wake:
            done = self._running[lane]
            if done is not None:
                self._cancelled.discard(done.id)
            self._running[lane] = None
            while not self._quit:
                kind = next((k for k in self._pending if self.lanes[k] == lane), None)
                if kind is not None:
                    job = self._running[lane] = self._pending.pop(kind)
                    return job
                self._wake.wait()
            return None

    def _loop(self, lane: str) -> None:
        lower_priority(LANE_NICENESS)
        while (job := self._next(lane)) is not None:
            context = Context(self, job)
            try:
                with running(context.should_stop, context.progress):  # jobs.cancel_point
                    value = job.job(context, *job.args)
                    if inspect.isgenerator(value):
                        value = self._drain(job, context, value)
                if value is _STOPPED:
                    continue
            except Cancelled:
                continue
            except Exception as exc:  # the window says so; the app keeps running
                self._report_failure(job, exc)
                continue
            if not context.should_stop():
                self.done.emit(job.kind, job.id, value)

    def _report_failure(self, job: _Job, exc: BaseException) -> None:
        """Log a failure and tell the window; neither after shutdown: the window may be gone,
        and so may the log's stream (a test's captured output, closed once the test ended)."""
        if self._quit:
            return
        if isinstance(exc, LeafError):  # bad input: said in the window (and by `gui FILE` once)
            log.debug("%s %d: %s", job.kind, job.id, exc)
        else:
            log.error("%s %d failed", job.kind, job.id, exc_info=exc)
        self.failed.emit(job.kind, job.id, exc)
        self._failed(job)

    def _drain(self, job: _Job, context: Context, values: Iterator[Any]) -> Any:
        try:
            while True:
                value = next(values)
                if context.should_stop():  # a newer interrupting job makes this stale
                    values.close()
                    return _STOPPED
                self.yielded.emit(job.kind, job.id, value)
        except StopIteration as stop:
            return stop.value

    def _reconstruct(self, context: Context, request: Request) -> Iterator[Outcome]:
        """The pipeline job: run, prepare the layers, yield the Outcome; then measure it (after
        it is shown, so that the metrics do not delay it) and return the seconds spent."""
        if self._pipeline is None or self._pipeline.leaf is not request.leaf:
            self._pipeline = Pipeline(request.leaf, self._store)
        result = self._pipeline.run(
            request.params, on_stage=context.stage, should_stop=context.should_stop
        )
        timings = dict(result.timings)
        start = time.perf_counter()
        layers = build_layers(result)
        timings["layers"] = time.perf_counter() - start
        # a pose fitted to the curves: the document takes it with its flat blade's sketch
        # (gui/model/pose_fits.py), made here, not on the main thread
        fitted = pose_fitted(request.leaf, result.leaf)
        sketch = Sketch.from_result(result) if request.derive or fitted else None
        outcome = Outcome(request, result, layers, timings, threading.get_ident(), sketch)
        yield outcome
        self._shown = outcome  # reported, so shown: a newer request's id is higher
        return self._measure(context, outcome)

    def _measure(self, context: Context, outcome: Outcome) -> float:
        """Measure `outcome` once it is drawn (if measure_after_drawn), on the pipeline's lane,
        here rather than on the main thread when the panel reads them; the seconds spent. Any
        newer request stops it at its next step (Cancelled: no `done`); the steps done are kept
        on the Result for the next try."""
        if self.measure_after_drawn:
            self._wait_drawn(outcome, context)
        stop = lambda: self._quit or context.newer_waiting()  # noqa: E731
        # a cold cache: measuring's kernels compiled in worker processes (this process would
        # hold the GIL for seconds), the status saying so as for the first run's; not counted
        # in the measurements' time
        compile_kernels(context.stage, should_stop=stop, tables=(MEASURE,))
        if stop():
            raise Cancelled
        start = time.perf_counter()
        outcome.result.measure(stop)
        return time.perf_counter() - start

    def _wait_drawn(self, outcome: Outcome, context: Context) -> None:
        """Wait until `outcome` is drawn (at most DRAWN_WAIT_S: a hidden window never draws);
        Cancelled when a newer request waits (a submit wakes this at once) or the worker
        shuts down."""
        deadline = time.monotonic() + DRAWN_WAIT_S
        with self._wake:
            while not outcome.drawn.is_set() and time.monotonic() < deadline:
                if self._quit or context.newer_waiting():
                    break
                self._wake.wait(DRAWN_POLL_S)
        if self._quit or context.newer_waiting():
            raise Cancelled  # a newer result follows: its measurements would be replaced at once

    def _failed(self, job: _Job) -> None:
        """After a pipeline job failed: measure the outcome shown, if it is not measured yet
        (its measuring gave way to the failed request) and no newer request waits."""
        outcome = self._shown
        if job.job != self._reconstruct or outcome is None or outcome.result.measured:
            return
        with self._wake:
            if PIPELINE not in self._pending and not self._quit:
                # the job id is the outcome's request id, which `done` reports with the seconds
                self._pending[PIPELINE] = _Job(
                    outcome.request.id, PIPELINE, self._measure, (outcome,), False
                )


def lower_priority(niceness: int) -> None:
    """Make the calling thread `niceness` nicer, at most 19 (Linux: a thread's niceness is its
    own, and the threads and processes it starts inherit it; elsewhere nothing: niceness is the
    whole process's)."""
    if not sys.platform.startswith("linux"):
        return
    thread = threading.get_native_id()
    with contextlib.suppress(OSError):  # a sandbox that refuses it: the app runs as before
        now = os.getpriority(os.PRIO_PROCESS, thread)
        os.setpriority(os.PRIO_PROCESS, thread, min(19, now + niceness))


def _plain(function: Callable[..., Any]) -> Callable[..., Any]:
    """A job for `submit` that runs `function(*args)` without the context."""

    def run(_context: Context, *args: Any) -> Any:
        return function(*args)

    return run


_STOPPED = object()
DRAWN_WAIT_S = 2.0  # the longest a result's measuring waits for the window to draw it
DRAWN_POLL_S = 0.01  # how often that wait looks whether it is drawn (a newer request wakes it)
