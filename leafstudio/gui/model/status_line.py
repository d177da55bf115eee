"""The status line's text as parts, without Qt (gui/qt/status.py shows it): a short head (the K
used, the grid, the times), then the notes on the result, each whole in the tooltip and the
status bar's notes button, the line showing the first.

With a scan open the line ran "K=3, grid 128: shown in 865 ms — note: Editing replaced the
scan's outline ... — note: the surface is 1.0% of the leaf's length from the scan ... — note:
the surface folds back on itself ..." (450 characters), cut at about 150 in a window 1280 wide:
the later notes and the measuring time after them were never on screen (closing32). As napari
keeps its status bar to one line and counts its notifications on a button beside it, the line
now says its head and first note, the button how many notes there are.
"""

from __future__ import annotations

from dataclasses import dataclass, replace


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
        first = self.notes[0]
        return f"{self.head} — {first[:1].upper()}{first[1:]}"

    @property
    def tip(self) -> str:
        """The tooltip: the head and its details, then every note whole, one a paragraph."""
        parts = [self.head, self.details, *(f"• {note}" for note in self.notes)]
        return "\n".join(part for part in parts if part)

    @property
    def count(self) -> str:
        """The notes button's words: "1 note", "3 notes", "" for none."""
        n = len(self.notes)
        return f"{n} note{'s' if n > 1 else ''}" if n else ""
