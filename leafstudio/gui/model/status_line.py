"""The status line's text as parts, without Qt (gui/qt/status.py shows it): a short head (the K
used, the grid, the times), then the notes on the result, each whole in the tooltip and the
status bar's notes button, the line showing the first.

With a scan open the line ran "K=3, grid 128: shown in 865 ms — note: Editing replaced the
scan's outline ... — note: the surface is 1.0% of the leaf's length from the scan ... — note:
the surface folds back on itself ..." (450 characters), cut at about 150 in a window 1280 wide:
the later notes and the measuring time after them were never on screen (closing32). As napari
keeps its status bar to one line and counts its notifications on a button beside it, the line
now says its head and first note, the button how many notes there are.

The first note was still cut ("…") at 1280 wide: soybean pot1_1's "The surface crumples over
3.6% of its area (bends tighter than ...): compare it with the scan's points before trusting its
shape" (229 characters) after a head of 55 (app34). A note too long for the line is shown by its
headline, the words before its first aside (" (", ": ", "; "), which says what is wrong in a
sentence of its own ("The surface crumples over 3.6% of its area"); the rest is one click away.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, replace

# where a note's headline ends: its first parenthesis, colon or semicolon (a comma does not:
# "vein 1, the midrib, seems written from the apex to the base (...)")
ASIDE = re.compile(r" \(|: |; ")
MORE = " (more under ⚠)"  # after a headline: the notes button holds the note whole


def said(note: str) -> str:
    """A note as the window says it, on the line, in its tooltips and in the notes box: as a
    sentence, its first letter capital (the tooltip said them in lower case, the box not)."""
    return note[:1].upper() + note[1:]


def headline(note: str) -> str:
    """The note's words before its first aside (ASIDE), as said; the whole note without one."""
    return said(ASIDE.split(note, maxsplit=1)[0])


@dataclass(frozen=True)
class StatusLine:
    """One status line.

    Attributes
    ----------
    head : str
        What the line says first (a result's K, grid and times; any other message whole).
    notes : tuple of str
        Notes on it, the first shown on the line after the head, all in the tooltip.
    details : str
        More for the tooltip only (each stage's time).
    """

    head: str
    notes: tuple[str, ...] = ()
    details: str = ""

    def noted(self, note: str) -> StatusLine:
        """The line with `note` added after its notes (said once)."""
        return self if note in self.notes else replace(self, notes=(*self.notes, note))

    def extended(self, more: str) -> StatusLine:
        """The line with `more` added to its head, before the notes (the measuring time: after
        them it was never seen)."""
        return replace(self, head=self.head + more)

    @property
    def text(self) -> str:
        """The one line: the head, then the first note."""
        if not self.notes:
            return self.head
        return f"{self.head} — {said(self.notes[0])}"

    def fitted(self, fits: Callable[[str], bool]) -> str:
        """The line as shown where `fits(text)` says whether a text fits: `text` when it fits,
        else the head and the first note's headline, with MORE where that fits too (the caller
        elides the line if even the headline does not fit: MORE cut to "(more un…" at 1024
        wide after "The surface is 3.0% of the leaf's length from the scan on average", the
        notes button beside it says there is more). The head (K, grid, the times) always comes
        first and whole."""
        if fits(self.text) or not self.notes:
            return self.text
        short = headline(self.notes[0])
        if short == said(self.notes[0]):
            return self.text
        more = f"{self.head} — {short}{MORE}"
        return more if fits(more) else f"{self.head} — {short}"

    @property
    def tip(self) -> str:
        """The tooltip: the head and its details, then every note whole, one a paragraph."""
        parts = [self.head, self.details, bullets(self.notes)]
        return "\n".join(part for part in parts if part)

    @property
    def count(self) -> str:
        """The notes button's words: "1 note", "3 notes", "" for none."""
        n = len(self.notes)
        return f"{n} note{'s' if n > 1 else ''}" if n else ""


def bullets(notes: tuple[str, ...]) -> str:
    """`notes` as a tooltip lists them: one a line, each as said, after a bullet."""
    return "\n".join(f"• {said(note)}" for note in notes)
