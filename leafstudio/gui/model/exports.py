"""Exports written in a process of their own, so that the window never waits on them.

A thread was not enough: the export's steps hold Python's global lock for long stretches (open3d's
decimation of each level of detail: about 0.4 s apiece; the first glTF write's imports: 1 s), and
the window's main thread cannot run meanwhile. One child process (spawned, never forked from the
Qt process; kept for the next export) runs the writer; its progress comes back through a queue
that the calling thread (the worker's export lane) relays to `progress`. The child is a process
of its own, so VTK's off-screen renders (a turntable, the steps figure) run on its main thread
too. No Qt here.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from leafstudio._shared.spawn import WorkerContext
from leafstudio.errors import LeafError

POLL_S = 0.05  # how often the waiting thread relays the child's progress

_reports: Any = None  # in the child: the queue its progress goes to


def _start_child(reports: Any) -> None:
    global _reports
    _reports = reports


def _child_progress(fraction: float, what: str) -> None:
    _reports.put((float(fraction), str(what)))


def _in_child(write: Callable[..., Any], args: tuple, kwargs: dict) -> Any:
    return write(*args, progress=_child_progress, **kwargs)


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
        try:
            future = pool.submit(_in_child, write, args, kwargs)
            while True:
                try:
                    progress(*reports.get(timeout=POLL_S))
                    continue
                except queue.Empty:
                    if future.done():
                        break
            return future.result()
        except BrokenProcessPool:
            with self._lock:
                self._pool = None  # a new one next time
            raise LeafError("the export's process ended before writing the file") from None

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
    result: Any, compared: list[tuple[str, Any]], path: str, progress: Callable[[float, str], Any]
) -> Any:
    """Write the lesson's steps on `result` and the `compared` forms (title, forms) as slides
    to `path` (render/step_slides.py: a .pdf, or a folder of PNGs with the PDF), telling
    `progress`; in the export process (matplotlib draws each slide)."""
    from leafstudio.render.step_slides import lesson_slides, write_slides

    progress(0.1, "drawing the slides")
    made = lesson_slides(result, compared)
    progress(0.6, "writing the slides")
    written = write_slides(made, path)
    progress(1.0, "done")
    return written
