"""File > Open photo's dialog, without Qt (issue 23, item 6): how big the leaf in a photo is.

Three ways, the first given wins: a length typed for the leaf (base to apex, opening.photo_length);
a ruler, two points the user clicks on the photo and the distance between them typed ("10 mm"),
which gives a pixel's size; the photo's own resolution (a scan's DPI, sources/photo_scale.py),
which read_photo_leaf takes when nothing else is given. With a unit (typed, the ruler's, or the
DPI), the leaf is made in millimetres, its real size, which the export offers next
(`real_length_text`). The Qt dialog (gui/qt/photo_dialog.py) shows the photo, passes clicks and
text here and shows `summary`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from leafstudio.errors import LeafError
from leafstudio.gui.model.opening import has_unit, photo_length
from leafstudio.sources.photo_scale import photo_dpi


@dataclass
class PhotoImport:
    """What File > Open photo's dialog holds.

    Attributes
    ----------
    path : str
        The photo.
    dpi : float or None
        The resolution the file records when it is a scale (photo_scale.photo_dpi).
    length : str
        The leaf's length as typed ("8cm", "2.5", "").
    ruler : list of (2,) float arrays
        The ruler's ends clicked on the photo, (column, row) pixels: none, one or two.
    distance : str
        The ruler's length as typed ("10 mm").
    base_end : str
        Where the leaf's base is in the photo, one of sources.photo.BASE_ENDS ("auto" finds it;
        "left", ...: as `leafstudio photo --base-end`).
    """

    path: str
    dpi: float | None = None
    length: str = ""
    ruler: list[np.ndarray] = field(default_factory=list)
    distance: str = ""
    base_end: str = "auto"

    @classmethod
    def of(cls, path: str, length: str = "") -> PhotoImport:
        """The dialog's start for `path`: its DPI read, `length` (the last one typed) offered."""
        return cls(str(path), photo_dpi(path), length)

    def click(self, point: tuple[float, float] | np.ndarray) -> None:
        """A click on the photo, in its pixels: the ruler's next end (a third click starts a
        new ruler)."""
        if len(self.ruler) == 2:
            self.ruler = []
        self.ruler.append(np.asarray(point, dtype=float))

    def ruler_pixels(self) -> float | None:
        """The ruler's length in pixels, None until both ends are clicked."""
        if len(self.ruler) < 2:
            return None
        return float(np.linalg.norm(self.ruler[1] - self.ruler[0]))

    def options(self) -> dict[str, float | str]:
        """read_document's options: {"length": ...}, {"pixel_size": ...} (the ruler's) or {}
        (the DPI, or length 1), with {"base_end": ...} when an end is named.

        Raises
        ------
        LeafError
            A length or distance that is not one, or a ruler half given.
        """
        ends = {"base_end": self.base_end} if self.base_end != "auto" else {}
        if self.length.strip():
            return {"length": photo_length(self.length), **ends}
        pixels = self.ruler_pixels()
        if not self.distance.strip():
            return ends
        if pixels is None or pixels < 1:
            raise LeafError("click the ruler's two ends on the photo, then type their distance")
        try:
            distance = photo_length(self.distance)
        except LeafError as exc:
            raise LeafError(f"the ruler's distance: {exc.problem}") from None
        assert distance is not None
        return {"pixel_size": distance / pixels, **ends}

    def from_what(self) -> str:
        """What sets the leaf's size: "length", "ruler", "dpi" or "" (nothing: length 1)."""
        if self.length.strip():
            return "length"
        if self.distance.strip():
            return "ruler"
        return "dpi" if self.dpi is not None else ""

    def real_size(self) -> bool:
        """Whether the leaf comes out at its real size, in millimetres."""
        how = self.from_what()
        if how == "length":
            return has_unit(self.length)
        if how == "ruler":
            return has_unit(self.distance)
        return how == "dpi"

    def summary(self) -> str:
        """One line for the dialog: what the leaf's size will come from and where its base is,
        or what is wrong."""
        try:
            options = self.options()
        except LeafError as exc:
            return str(exc)
        if self.base_end == "auto":
            base = ("The base is found in the photo: its petiole, notch or veins, else the wider "
                    "end.")  # fmt: skip
        else:
            base = f"The leaf's base at the {self.base_end} end of the photo."
        return f"{self._size(options)} {base}"

    def _size(self, options: dict[str, float | str]) -> str:
        """What the leaf's size will come from (summary)."""
        how, real = self.from_what(), self.real_size()
        units = "at its real size, in millimetres" if real else "in the leaf's own units"
        if how == "length":
            return f"The leaf will be {self.length.strip()} long, base to apex ({units})."
        if how == "ruler":
            per = f"{options['pixel_size']:.4g}{' mm' if real else ''}"
            return (f"The ruler: {self.ruler_pixels():.0f} pixels are {self.distance.strip()} "
                    f"({per} a pixel): the leaf {units}.")  # fmt: skip
        if how == "dpi":
            return (f"The photo records {self.dpi:g} DPI: the leaf at its real size, in "
                    "millimetres. Type a length or use the ruler to override it.")  # fmt: skip
        clicks = "; click the ruler's second end" if len(self.ruler) == 1 else ""
        return ("The photo records no scale: the leaf will be length 1. Type its length, or "
                f"click two points on the photo and type their distance{clicks}.")  # fmt: skip


def real_length_text(boundary: np.ndarray) -> str:
    """A photo leaf's length in millimetres as the export's length field takes it ("83.2mm"):
    base at the origin, apex on +x (the forms' convention)."""
    return f"{float(np.max(boundary[:, 0])):.4g}mm"
