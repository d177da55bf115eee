"""Handles on background jobs, without Qt: a job started on the worker (or run at once, without
a window) returns a `Job` whose own `done` and `failed` events say how it ended, as superqt's
worker signals do, so that nothing has to route answers by the job's kind.

A `Run` is how the session starts side jobs: `run(kind, function, *args) -> Job`, `kind` naming
the worker's lane and what a newer job of that kind replaces. The window passes
`Worker.start` (gui/qt/worker.py: off the main thread, reports delivered on it); `run_now`
runs the job at once, for a session driven without a window.

A job tells how far it has come with `_shared/progress.report(fraction, what)` (the readers do,
after each block of lines): its handle's `progressed` event hears it, on the main thread.

Cancelling is cooperative: `Job.cancel()` drops the job's answer at once and asks the job to
stop; a long job calls `cancel_point()` between its steps, which raises Cancelled once its job
was cancelled (or superseded), and the worker ends it without a report.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from leafstudio._shared import progress
from leafstudio.core.pipeline import Cancelled
from leafstudio.errors import LeafError
from leafstudio.gui.model.history import Event

log = logging.getLogger("leafstudio.gui")

Run = Callable[..., "Job"]  # run(kind, function, *args) -> Job


class Job:
    """One job's handle: its id and how it ended.

    Events
    ------
    done(value)
        The job's return value.
    failed(BaseException)
        What it raised (already logged).
    progressed(float | None, str)
        How far it has come (None: not known) and what it is doing, while it runs.

    A callback connected with `on_done` / `on_failed` after the job ended is called at once,
    one connected with `on_progress` hears the progress reported before it too.
    """

    def __init__(self, job_id: int = 0) -> None:
        self.id = job_id
        self.done, self.failed, self.progressed = Event(), Event(), Event()
        self._progress: list[tuple[float | None, str]] = []  # what was reported so far
        self.progressed.connect(lambda *told: self._progress.append(told))
        self._end: tuple[str, object] | None = None
        self.canceller: Callable[[], object] | None = None  # set by whoever runs the job

    @property
    def finished(self) -> bool:
        return self._end is not None

    @property
    def cancelled(self) -> bool:
        return self._end is not None and self._end[0] == "cancelled"

    def cancel(self) -> None:
        """Drop the job's answer (neither event fires any more) and ask it to stop at its next
        `cancel_point`. Nothing when it has ended."""
        if self._end is None:
            self._end = ("cancelled", None)
            if self.canceller is not None:
                self.canceller()

    @property
    def succeeded(self) -> bool:
        """True once it has ended with a value."""
        return self._end is not None and self._end[0] == "done"

    def finish(self, value: object) -> None:
        """Report the job's value (on the main thread)."""
        if self._end is None:
            self._end = ("done", value)
            self.done.emit(value)

    def fail(self, exc: BaseException) -> None:
        """Report the job's failure (on the main thread)."""
        if self._end is None:
            self._end = ("failed", exc)
            self.failed.emit(exc)

    def on_done(self, callback: Callable[[Any], object]) -> Job:
        self.done.connect(callback)
        if self._end is not None and self._end[0] == "done":
            callback(self._end[1])
        return self

    def on_progress(self, callback: Callable[[float | None, str], object]) -> Job:
        for told in self._progress:  # a job run at once (run_now) reported before this
            callback(*told)
        self.progressed.connect(callback)
        return self

    def on_failed(self, callback: Callable[[BaseException], object]) -> Job:
        self.failed.connect(callback)
        if self._end is not None and self._end[0] == "failed":
            callback(self._end[1])
        return self


def describe(exc: BaseException) -> str:
    """The one line the window shows for a failure (the traceback goes to the log)."""
    if isinstance(exc, LeafError):
        return str(exc)
    return f"{type(exc).__name__}: {exc} (details in the log)"


_running = threading.local()  # the stop check of the job running on this thread


@contextmanager
def running(
    should_stop: Callable[[], bool], listener: progress.Listener | None = None
) -> Iterator[None]:
    """Within it, `cancel_point()` on this thread asks `should_stop` (the worker's job loop) and
    `progress.report` tells `listener`, then is a cancel point too (a scan's extraction, which
    knows nothing of jobs, stops at its next report)."""
    before = getattr(_running, "should_stop", None)
    _running.should_stop = should_stop

    def told(fraction: float | None, what: str) -> None:
        if listener is not None:
            listener(fraction, what)
        cancel_point()

    try:
        with progress.reporting(told):
            yield
    finally:
        _running.should_stop = before


def cancel_point() -> None:
    """Raise Cancelled when the job running on this thread was cancelled or superseded; nothing
    outside a job. Long jobs call it between their steps."""
    should_stop = getattr(_running, "should_stop", None)
    if should_stop is not None and should_stop():
        raise Cancelled


def run_now(kind: str, function: Callable[..., Any], *args: Any) -> Job:
    """Run `function(*args)` at once and return its ended handle (a session without a window)."""
    job = Job()
    try:
        with progress.reporting(job.progressed.emit):
            value = function(*args)
    except LeafError as exc:
        log.info("%s: %s", kind, exc)
        job.fail(exc)
    except Exception as exc:  # reported as the worker reports it: the session says so
        log.error("%s failed", kind, exc_info=exc)
        job.fail(exc)
    else:
        job.finish(value)
    return job
