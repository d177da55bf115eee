"""Big files and long work in the window: it never waits for them (behaviour, not timings; the
figures are benchmarks/bench_gui.py's)."""

from __future__ import annotations

import threading

from .conftest import close_window


def test_closing_does_not_wait_for_a_job_that_cannot_stop(window, qtbot):
    started, release, ended = threading.Event(), threading.Event(), threading.Event()

    def long_step() -> None:  # a compiled kernel or a file read: it never checks should_stop
        started.set()
        release.wait(5)  # the old close waited up to 10 s for it
        ended.set()

    window.worker.start("open", long_step)
    assert started.wait(10)
    close_window(window)
    assert not ended.is_set()  # closed while the job still runs: not joined
    release.set()
    assert ended.wait(10)
