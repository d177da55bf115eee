"""The status line's parts (gui/model/status_line.py): its head whole, then its first note, by
its headline where the whole does not fit; every note said alike everywhere."""

from __future__ import annotations

from leafstudio.analysis.fidelity import scan_warnings
from leafstudio.gui.model.status_line import MORE, StatusLine, bullets, headline, said

HEAD = "K = 3, grid 128: shown in 644 ms · measured in 30 ms"
(CRUMPLES,) = scan_warnings({"length": 1.0, "mean": 0.001, "crumpled": 0.036})


def test_a_note_too_long_for_the_line_is_said_by_its_headline_after_the_whole_head():
    line = StatusLine(HEAD, (CRUMPLES, "no veins given: the leaf is flat"))
    assert line.fitted(lambda text: True) == line.text  # room: the note whole
    short = line.fitted(lambda text: len(text) <= 150)  # pot1_1's line: 284 characters
    assert short == f"{HEAD} — The surface crumples over 3.6% of its area{MORE}"
    assert len(short) <= 150


def test_a_headline_ends_at_the_first_aside_never_at_a_comma():
    assert headline("vein 1, the midrib, seems written from the apex (3 of 4 side veins)") == (
        "Vein 1, the midrib, seems written from the apex"
    )
    assert headline("veins meet at different heights in 3 places (most: veins 1 and 2 ...)") == (
        "Veins meet at different heights in 3 places"
    )
    long = "a note with no aside at all " * 5
    assert StatusLine(HEAD, (long,)).fitted(lambda text: False) == f"{HEAD} — {said(long)}"


def test_every_note_is_said_as_a_sentence_in_the_line_and_its_tips():
    line = StatusLine(HEAD, ("the surface folds back on itself", "Already a sentence"))
    assert line.text.endswith("— The surface folds back on itself")
    assert bullets(line.notes) == "• The surface folds back on itself\n• Already a sentence"
    assert line.tip.endswith(bullets(line.notes))
