"""Main-thread work put off to a later turn of the event loop, one piece per turn (issue 24).

A piece of work "in its own turn" (a result drawn after the session's work on it, a render, the
layers that waited for one) must let due timers and input in before it, or two pieces make one
stall. A zero-delay call does not: it is a posted event, and Qt runs posted events before due
timers, so a chain of them ran as one (bench_gui's 5 ms timer saw 93 ms of main-thread CPU
between two ticks while a 2-million-point scan opened). And two calls put off by the same delay
fire in the same pass over the timers. So `later` queues the call, and one timer of
NEXT_TURN_MS runs the first call queued, then arms itself again for the next: every due timer,
and the input the window system queued, comes in between.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

import shiboken6
from PySide6.QtCore import QObject, QTimer

NEXT_TURN_MS = 1  # a timer, not a zero-delay call (see above)

_queue: deque[tuple[QObject, Callable[[], object]]] = deque()
_armed = [False]


def later(owner: QObject, call: Callable[[], object]) -> None:
    """Run `call` in a later turn of the event loop, after the calls queued before it, each in
    a turn of its own; not if `owner` (the widget it works on) is deleted by then."""
    _queue.append((owner, call))
    if not _armed[0]:
        _armed[0] = True
        QTimer.singleShot(NEXT_TURN_MS, _run_one)


def _run_one() -> None:
    _armed[0] = False
    while _queue:
        owner, call = _queue.popleft()
        if shiboken6.isValid(owner):
            break
    else:
        return
    try:
        call()
    finally:
        if _queue and not _armed[0]:
            _armed[0] = True
            QTimer.singleShot(NEXT_TURN_MS, _run_one)
