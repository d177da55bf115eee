"""Exports written in a process of their own, so that the window never waits on them.

A thread was not enough: the export's steps hold Python's global lock for long stretches (open3d's
decimation of each level of detail: about 0.4 s apiece; the first glTF write's imports: 1 s), and
the window's main thread cannot run meanwhile. One child process (spawned, never forked from the
Qt process; kept for the next export) runs the writer; its progress comes back through a queue
that the calling thread (the worker's export lane) relays to `progress`, up to an end mark the
child puts after the writer's last report (the writer's value comes back through the pool's own
pipe, and could overtake reports still in the queue's). The child is a process
of its own, so VTK's off-screen renders (a turntable, the steps figure) run on its main thread
too. No Qt here.
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from leafstudio._shared.spawn import WorkerContext
from leafstudio.core.plane import Frame
from leafstudio.errors import LeafError

POLL_S = 0.05  # how often the waiting thread relays the child's progress
END_WAIT_S = 5.0  # how long a finished export's end mark may lag behind its value

_reports: Any = None  # in the child: the queue its progress goes to


def _start_child(reports: Any) -> None:
    global _reports
    _reports = reports


def _in_child(run: int, write: Callable[..., Any], args: tuple, kwargs: dict) -> Any:
    """`write` in the child, its reports tagged with `run`; the end mark (fraction None) after
    them, whether it returned or raised."""

    def progress(fraction: float, what: str) -> None:
        _reports.put((run, float(fraction), str(what)))

    try:
        return write(*args, progress=progress, **kwargs)
    finally:
        _reports.put((run, None, ""))


def _gone(future: Future) -> bool:
    """Whether the child ended without its end mark: it died, or the pool was shut down."""
    if not future.done():
        return False
    return future.cancelled() or isinstance(future.exception(), BrokenProcessPool)


def _unmeasured() -> None:
    """What a Result's Measuring (core/result.py: a lock, a generator under way) becomes in the
    export process: none, the exports read no metrics."""


def _portable() -> None:
    """Send Results to the child without their Measuring (it cannot be pickled)."""
    from multiprocessing.reduction import ForkingPickler

    from leafstudio.core.result import Measuring

    ForkingPickler.register(Measuring, lambda _measuring: (_unmeasured, ()))


class ExportProcess:
    """The process exports are written in, started at the first export and kept."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._pool: ProcessPoolExecutor | None = None
        self._reports: Any = None
        self._runs = 0  # exports run so far: each one's tag on its reports

    def _ready(self) -> tuple[ProcessPoolExecutor, Any]:
        with self._lock:
            if self._pool is None:
                _portable()
                context = WorkerContext()  # a plain script has no __main__ guard
                self._reports = context.Queue()
                self._pool = ProcessPoolExecutor(
                    1, mp_context=context, initializer=_start_child, initargs=(self._reports,)
                )
            return self._pool, self._reports

    def run(
        self, write: Callable[..., Any], *args: Any, progress: Callable[[float, str], Any],
        **kwargs: Any,
    ) -> Any:  # fmt: skip
        """`write(*args, progress=..., **kwargs)` in the child; waits (without the lock) and
        relays its progress; returns its value or raises what it raised (LeafError if the
        child died)."""
        pool, reports = self._ready()
        self._runs += 1
        try:
            future = pool.submit(_in_child, self._runs, write, args, kwargs)
            self._relay(self._runs, future, reports, progress)
            return future.result()
        except BrokenProcessPool:
            with self._lock:
                self._pool = None  # a new one next time, with a new queue: this one's pipe
                reports.close()  # and sending thread go with it
            raise LeafError("the export's process ended before writing the file") from None

    @staticmethod
    def _relay(
        run: int, future: Future, reports: Any, progress: Callable[[float, str], Any]
    ) -> None:
        """Pass run `run`'s reports to `progress` until its end mark (or the child's end)."""
        done_at: float | None = None
        while True:
            try:
                tag, fraction, what = reports.get(timeout=POLL_S)
            except queue.Empty:
                if future.done() and done_at is None:
                    done_at = time.monotonic()
                late = done_at is not None and time.monotonic() - done_at > END_WAIT_S
                if late or _gone(future):
                    return
                continue
            if tag != run:
                continue  # an earlier run's, whose waiting thread stopped early
            if fraction is None:
                return
            progress(fraction, what)

    def close(self) -> None:
        """End the child at once (the app closes: a file half made is never in place, every
        export writes atomically)."""
        with self._lock:
            pool, self._pool = self._pool, None
        if pool is None:
            return
        for process in list(getattr(pool, "_processes", {}).values()):  # no public way
            process.terminate()
        pool.shutdown(wait=False, cancel_futures=True)


def slide(kind: str, result: Any, path: str, progress: Callable[[float, str], Any]) -> Any:
    """Write a turntable (kind "turntable") or the steps figure of `result` to `path`, telling
    `progress`; in the export process (it renders with VTK off screen)."""
    from leafstudio.render.slides import render_steps, render_turntable

    if kind == "turntable":
        written = render_turntable(result, path, progress=progress)
    else:
        progress(0.1, "rendering the steps")
        written = render_steps(result, path)
    progress(1.0, "done")
    return written


def slides(
    result: Any,
    compared: list[tuple[str, Any]],
    path: str,
    progress: Callable[[float, str], Any],
    frame: Frame | None = None,
) -> Any:
    """Write the lesson's steps on `result` (drawn on `frame`: the lesson's,
    step_slides.plan_frame) and the `compared` forms (title, forms) as slides to `path`
    (render/step_slides.py: a .pdf, or a folder of PNGs with the PDF), telling `progress`; in
    the export process (matplotlib draws each slide)."""
    from leafstudio.render.step_slides import lesson_slides, write_slides

    progress(0.1, "drawing the slides")
    made = lesson_slides(result, compared, frame)
    progress(0.6, "writing the slides")
    written = write_slides(made, path)
    progress(1.0, "done")
    return written
