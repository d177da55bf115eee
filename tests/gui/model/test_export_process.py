"""The export process (gui/model/exports.py) relays every progress report its writer made, the
last one included, before it returns (CI, session 6: the window's export test waited in vain for
its "done" report, which was still in the queue's pipe when the writer's value arrived)."""

from __future__ import annotations

import os
import threading
from collections.abc import Callable

import pytest

from leafstudio.errors import LeafError
from leafstudio.gui.model.exports import ExportProcess

REPORTS = 2000


def _chatty(count: int, progress: Callable[[float, str], object]) -> int:
    """A writer that reports `count` times and returns at once after its last report."""
    for step in range(count):
        progress((step + 1) / count, f"step {step + 1}")
    return count


def _late_last_report(progress: Callable[[float, str], object]) -> str:
    """A writer whose last report reaches the pipe after its value does: the child's queue
    sends from a thread of its own, held here (through the queue's own lock) for 0.5 s past the
    writer's return, as a busy machine can hold it."""
    from leafstudio.gui.model import exports

    progress(0.5, "half way")
    progress(1.0, "done")
    held = exports._reports._notempty  # what the queue's sending thread waits on
    held.acquire()
    threading.Timer(0.5, held.release).start()
    return "written"


def _failing(progress: Callable[[float, str], object]) -> None:
    progress(0.5, "half way")
    raise LeafError("the file cannot be written")


def _into(seen: list[float]) -> Callable[[float, str], None]:
    """A progress callback that keeps the fractions it is told."""
    return lambda fraction, _what: seen.append(fraction)


def _dying(progress: Callable[[float, str], object]) -> None:
    progress(0.25, "started")
    os._exit(3)  # as a crash in a native library ends the child


@pytest.fixture(scope="module")
def exports():
    process = ExportProcess()
    yield process
    process.close()


def test_every_report_arrives_before_the_export_returns(exports):
    for _run in range(3):  # the child is kept: no report of one run leaks into the next
        seen: list[float] = []
        assert exports.run(_chatty, REPORTS, progress=_into(seen)) == REPORTS
        assert len(seen) == REPORTS and seen[-1] == 1.0


def test_a_last_report_that_comes_late_still_arrives(exports):
    seen: list[float] = []
    assert exports.run(_late_last_report, progress=_into(seen)) == "written"
    assert seen == [0.5, 1.0]


def test_a_failed_export_relays_its_reports_and_raises(exports):
    seen: list[float] = []
    with pytest.raises(LeafError, match="cannot be written"):
        exports.run(_failing, progress=_into(seen))
    assert seen == [0.5]


def test_a_child_that_dies_is_said_and_the_next_export_gets_a_new_one(exports):
    with pytest.raises(LeafError, match="ended before writing"):
        exports.run(_dying, progress=_into([]))
    dead_reports = exports._reports
    seen: list[float] = []
    assert exports.run(_chatty, 10, progress=_into(seen)) == 10
    assert seen[-1] == 1.0 and len(seen) == 10
    assert exports._reports is not dead_reports and dead_reports._closed  # its pipe let go
