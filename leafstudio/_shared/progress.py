"""How far a long read has come, told to whoever listens on this thread (no Qt, no leaf
knowledge).

A reader calls `report(fraction, what)` as it goes (sources' readers: after each block of lines);
nothing happens unless a listener was installed on the thread with `reporting(callback)`: the
app's worker (gui/model/jobs.py), which shows a fraction in the busy bar, or the process a big
file is read in (gui/model/reading.py), which sends it to the app. Passing a callback through
every reader's signature would touch the public API (`ls.load_leaf`) for the app's sake.

A step inside a longer piece of work reports its own fractions within `share(start, end)`: they
reach the listener as that part of the whole (a scan's sheet, fitted within its extraction). A
report is also a point where the work may stop: the app's listener raises Cancelled there once
the job was cancelled (gui/model/jobs.running).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

Listener = Callable[[float | None, str], object]  # (fraction done in [0, 1] or None, what)

_local = threading.local()


@contextmanager
def reporting(listener: Listener | None) -> Iterator[None]:
    """Within it, `report` on this thread calls `listener` (None: nobody listens)."""
    before = getattr(_local, "listener", None)
    _local.listener = listener
    try:
        yield
    finally:
        _local.listener = before


def report(fraction: float | None, what: str = "reading") -> None:
    """Tell this thread's listener that `fraction` of `what` is done (None: a step whose length
    is not known begins); nothing if none listens."""
    listener = getattr(_local, "listener", None)
    if listener is not None:
        listener(None if fraction is None else min(max(float(fraction), 0.0), 1.0), what)


@contextmanager
def share(start: float, end: float) -> Iterator[None]:
    """Within it, a fraction f reported on this thread reaches the listener as start + f (end -
    start): a step's own progress, as its part of the work around it."""
    before = getattr(_local, "listener", None)
    if before is None:
        yield
        return

    def scaled(fraction: float | None, what: str) -> object:
        return before(None if fraction is None else start + fraction * (end - start), what)

    with reporting(scaled):
        yield
