"""A command given a FIFO, run in this process (no child's 2 s of imports) without risking a
test that waits for ever: should the command open the pipe instead of refusing it, a watchdog
opens the pipe's other end after a while, releasing it, and the test fails."""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Iterator
from pathlib import Path

RELEASE_S = 60.0  # a refusal is at once; a command still in the pipe after this opened it


@contextlib.contextmanager
def released(fifos: list[Path], seconds: float = RELEASE_S) -> Iterator[list[Path]]:
    """While the block runs, a FIFO of `fifos` a reader waits on for `seconds` is opened for
    writing and closed (its reader then reads an empty file); yields the list of those it
    released, empty when none was waited on."""
    done = threading.Event()
    freed: list[Path] = []

    def watch() -> None:
        if done.wait(seconds):
            return
        while not done.wait(0.05):  # until the block ends: a reader may open a pipe again
            for fifo in fifos:
                try:  # refused (ENXIO) while no reader has it open
                    os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
                    freed.append(fifo)
                except OSError:
                    pass

    watchdog = threading.Thread(target=watch, name="fifo-watchdog", daemon=True)
    watchdog.start()
    try:
        yield freed
    finally:
        done.set()
        watchdog.join()
