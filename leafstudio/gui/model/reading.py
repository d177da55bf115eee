"""A big file is read in a process of its own (no Qt here).

Reading and extracting a 2M-point scan is mostly Python and numpy work that holds the
interpreter's lock for long stretches: in a thread of the app's process it stalled the window's
main thread for up to a second at a time, and Cancel could only drop its answer while the read
went on. In a child process (spawned: the window's process has threads) it shares nothing with
the window, and Cancel ends it at once. A small file is read in the thread: a child costs a few
seconds of start-up (imports), more than such a file takes. The child does not import the
parent's `__main__` (_shared/spawn.py): a plain script driving a Session, without an
`if __name__ == "__main__":` guard, would otherwise run again in it and fail. What the readers
report in the child (_shared/progress.report) comes back through the pipe and is reported again
in the waiting thread, where the app's busy bar hears it.
"""

from __future__ import annotations

import logging
import os
import traceback
from collections.abc import Callable
from typing import Any

from leafstudio._shared import progress
from leafstudio._shared.spawn import WorkerContext
from leafstudio.errors import LeafError
from leafstudio.gui.model.jobs import cancel_point

log = logging.getLogger("leafstudio.gui")

BIG_FILE_BYTES = 8_000_000  # a regular file above this size is read in a process of its own
POLL_S = 0.05  # how often the waiting thread looks for Cancel
# the child's niceness above the app's: its imports and read (seconds of CPU) then yield the
# cores to the window's main thread, which waited 80-400 ms at a time for one on a 2-core host
# while a child only started (issue 24); Linux and macOS (os.nice), at most 19
CHILD_NICENESS = 10


def is_big(path: str) -> bool:
    """True for a regular file of more than BIG_FILE_BYTES."""
    try:
        return os.path.isfile(path) and os.path.getsize(path) > BIG_FILE_BYTES
    except OSError:
        return False


def _child(connection: Any, function: Callable[..., Any], args: tuple) -> None:
    """In the child: run `function(*args)`, sending its progress, and send how it ended."""
    if hasattr(os, "nice"):
        os.nice(CHILD_NICENESS)

    def tell(fraction: float | None, what: str) -> None:
        connection.send(("progress", fraction, what))

    try:
        with progress.reporting(tell):
            answer: tuple = ("done", function(*args))
    except LeafError as exc:
        answer = ("leaf", exc.problem, exc.source)
    except Exception as exc:  # a bug: named in the parent, its traceback logged there
        answer = ("error", f"{type(exc).__name__}: {exc}", traceback.format_exc())
    connection.send(answer)
    connection.close()


def read_apart(function: Callable[..., Any], *args: Any) -> Any:
    """`function(*args)` in a fresh process, waiting here; what it returns must pickle. Its
    progress (_shared/progress.report in the child) is reported again on this thread.

    Raises
    ------
    LeafError
        What the function raised as one (bad input).
    Cancelled
        The job was cancelled (jobs.cancel_point): the process is ended at once.
    RuntimeError
        The function failed otherwise, or the process died.
    """
    context = WorkerContext()
    receive, send = context.Pipe(duplex=False)
    process = context.Process(target=_child, args=(send, function, args), daemon=True)
    process.start()
    send.close()  # the child's end: the parent sees EOF if the child dies
    try:
        while True:
            cancel_point()
            if not receive.poll(POLL_S):
                continue
            try:
                answer = receive.recv()
            except EOFError:
                raise RuntimeError(
                    f"the reading process ended (exit code {process.exitcode})"
                ) from None
            if answer[0] != "progress":
                break
            progress.report(*answer[1:])
    finally:
        if process.is_alive():
            process.terminate()
        process.join(1.0)
        receive.close()
    if answer[0] == "leaf":
        raise LeafError(answer[1], answer[2])
    if answer[0] == "error":
        log.error("reading in a process of its own failed:\n%s", answer[2])
        raise RuntimeError(answer[1])
    return answer[1]
