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


def test_a_headline_with_no_room_for_its_more_is_not_cut_inside_it():
    """review34: at 1024 wide the line read "... from the scan on average (more un…": the
    headline and MORE did not fit, and the window's elision cut MORE. Without room for MORE
    the headline stands alone (the notes button beside it says there is more)."""
    far = scan_warnings({"length": 1.0, "mean": 0.03, "p95": 0.08})[0]
    line = StatusLine(HEAD, (far,))
    short = f"{HEAD} — The surface is 3.0% of the leaf's length from the scan on average"
    assert line.fitted(lambda text: len(text) <= len(short)) == short
    assert line.fitted(lambda text: len(text) <= len(short + MORE)) == short + MORE


def test_every_note_the_app_makes_has_a_headline_that_says_what_is_wrong():
    """review34: "the surface folds back on itself at 1.2% of its edges (creases past 90°) and
    crumples over 3.6% of its area (...)" was headed "The surface folds back on itself at 1.2%
    of its edges", the crumpling dropped; a texture that could not be made, "texture: ...",
    was headed "Texture"."""
    from unittest.mock import MagicMock

    from leafstudio.gui.model.side import SideJobs

    (both,) = scan_warnings({"length": 1.0, "mean": 0.001, "crumpled": 0.036, "folded": 0.012})
    assert headline(both) == (
        "The surface folds back on itself at 1.2% of its edges and crumples over 3.6% of its area"
    )
    assert headline(CRUMPLES) == "The surface crumples over 3.6% of its area"  # as before
    notes = []
    side = MagicMock(_texture_due=(job := object(),), note=MagicMock(emit=notes.append))
    side.session.texture.return_value = "auto"
    SideJobs._texture_failed(side, job, OSError("cannot write the texture's image"))
    assert len(notes) == 1 and len(headline(notes[0]).split()) >= 4, notes
