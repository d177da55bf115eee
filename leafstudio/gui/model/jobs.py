"""Handles on background jobs, without Qt: a job started on the worker (or run at once, without
a window) returns a `Job` whose own `done` and `failed` events say how it ended, as superqt's
worker signals do, so that nothing has to route answers by the job's kind.

A `Run` is how the session starts side jobs: `run(kind, function, *args) -> Job`, `kind` naming
the worker's lane and what a newer job of that kind replaces. The window passes
`Worker.start` (gui/qt/worker.py: off the main thread, reports delivered on it); `run_now`
runs the job at once, for a session driven without a window.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

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

    A callback connected with `on_done` / `on_failed` after the job ended is called at once.
    """

    def __init__(self, job_id: int = 0) -> None:
        self.id = job_id
        self.done, self.failed = Event(), Event()
        self._end: tuple[str, object] | None = None

    @property
    def finished(self) -> bool:
        return self._end is not None

    def finish(self, value: object) -> None:
        """Report the job's value (on the main thread)."""
        self._end = ("done", value)
        self.done.emit(value)

    def fail(self, exc: BaseException) -> None:
        """Report the job's failure (on the main thread)."""
        self._end = ("failed", exc)
        self.failed.emit(exc)

    def on_done(self, callback: Callable[[Any], object]) -> Job:
        self.done.connect(callback)
        if self._end is not None and self._end[0] == "done":
            callback(self._end[1])
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


def run_now(kind: str, function: Callable[..., Any], *args: Any) -> Job:
    """Run `function(*args)` at once and return its ended handle (a session without a window)."""
    job = Job()
    try:
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
