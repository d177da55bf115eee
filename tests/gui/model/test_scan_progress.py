"""A scan's extraction in the app (issue 24): the busy bar shows how far it has come (it turned
without a fraction from the end of the read to the leaf), and Cancel stops it at its next step
(it ran to its end)."""

from __future__ import annotations

import pytest

from leafstudio._shared import progress
from leafstudio.core.pipeline import Cancelled
from leafstudio.gui.model import opening
from leafstudio.gui.model.jobs import running
from tests.gui.builders import six_column_scan, write_points


def _extracting(heard: list) -> list[float | None]:
    """The fractions heard after the read (the extraction's and its sheet's)."""
    return [fraction for fraction, doing in heard if doing != "reading"]


def test_a_scan_reports_how_far_its_extraction_has_come(tmp_path):
    path = write_points(tmp_path / "scan.txt", six_column_scan())
    heard: list = []
    with running(lambda: False, lambda fraction, doing: heard.append((fraction, doing))):
        document = opening.read_document(path, as_scan=True)
    assert document.leaf.bend is not None  # the blade was unrolled: its sheet reported too
    fractions = _extracting(heard)
    assert None not in fractions
    assert fractions == sorted(fractions) and fractions[0] == 0.0 and fractions[-1] == 1.0
    assert len(set(fractions)) >= 10
    assert {doing for _, doing in heard} >= {"finding the leaf in the scan", "unrolling the blade"}


def test_cancel_stops_a_scan_extraction_at_its_next_step(tmp_path):
    path = write_points(tmp_path / "scan.txt", six_column_scan())
    heard: list = []

    def cancelled() -> bool:  # Cancel pressed once a third of the extraction was reported
        return any(fraction >= 0.3 for fraction in _extracting(heard) if fraction is not None)

    listen = lambda fraction, doing: heard.append((fraction, doing))  # noqa: E731
    with running(cancelled, listen), pytest.raises(Cancelled):
        opening.read_document(path, as_scan=True)
    late = [f for f in _extracting(heard) if f is not None and f >= 0.3]
    assert len(late) == 1  # nothing ran on after the report that saw the Cancel


def test_a_step_reports_its_fractions_as_its_share_of_the_whole():
    heard: list = []
    with progress.reporting(lambda fraction, doing: heard.append((fraction, doing))):
        progress.report(0.0, "all")
        with progress.share(0.5, 0.9):
            progress.report(0.5, "a step")
            progress.report(None, "a step")
        progress.report(1.0, "all")
    assert heard == [(0.0, "all"), (pytest.approx(0.7), "a step"), (None, "a step"), (1.0, "all")]
    with progress.share(0.5, 0.9):  # nobody listens: nothing happens
        progress.report(0.5)
