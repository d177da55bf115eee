"""Forms side by side with their terms, drawn with matplotlib (no display needed): the app's
Compare forms view and the slides show this one figure.

Each form is drawn from above (outline filled, veins over it) at one scale for all, so a wider
or longer leaf looks it; under it, in words large enough for a projector, the terms in which
the forms differ and what they mean (forms/glossary.compared_terms).
"""

from __future__ import annotations

import textwrap
from typing import Any

import numpy as np

from leafstudio.forms.glossary import compared_terms
from leafstudio.forms.make import Form

BLADE, EDGE, VEIN = "#8cc46a", "#2f5d1e", "#f4faee"
FIGURE_SIZE = (16.0, 9.0)  # inches: a 16:9 slide (1600 x 900 pixels at 100 dpi)
TITLE_PT, TEXT_PT = 26, 17  # points: read from the back of a classroom
CHAR_WIDTH = 0.58  # a character's mean width, in font sizes (DejaVu Sans)
LINE = 1.25  # a line's height, in font sizes
TEXT_SHARE = 0.8  # of a column's width its definition's lines fill at the mean character width
# (0.9 left 'running' touching the next column's 'secondary' among four: wide letters)


def upright(xy: np.ndarray) -> np.ndarray:
    """Plane points turned a quarter: the apex (+x) up, as a leaf is drawn in a textbook."""
    return np.column_stack([-xy[:, 1], xy[:, 0]])


def draw_outline(ax: Any, outline: np.ndarray, veins: tuple[np.ndarray, ...] | list) -> None:
    """A leaf seen from above on `ax`, apex up: (n, 2) `outline` filled, each (m, 2) vein a
    line (plane coordinates, the forms' convention)."""
    up = upright(outline)
    ax.fill(up[:, 0], up[:, 1], facecolor=BLADE, edgecolor=EDGE, linewidth=1.5)
    for vein in veins:
        v = upright(vein)
        ax.plot(v[:, 0], v[:, 1], color=VEIN, linewidth=1.2, solid_capstyle="round")
    ax.set_aspect("equal")
    ax.set_axis_off()


def _write_terms(ax: Any, terms: list[tuple[str, str, str]], chars: int, name_pt: int) -> None:
    """Each term's name (bold) and its definition wrapped at `chars`, down from the top of
    `ax`, spaced in points so that no line overlaps the next."""
    ax.set_axis_off()
    down = 0.0  # points below the top
    for kind, term, text in terms:
        name = term if kind == "shape" else f"{term} {kind}"
        for words, size, weight in (
            (name, name_pt, "bold"),
            (textwrap.fill(text, chars), TEXT_PT, "normal"),
        ):
            ax.annotate(
                words,
                (0.5, 1.0),
                xycoords="axes fraction",
                xytext=(0, -down),
                textcoords="offset points",
                fontsize=size,
                weight=weight,
                ha="center",
                va="top",
            )
            down += LINE * size * (words.count("\n") + 1)
        down += TEXT_PT  # a gap before the next term


def compare_figure(forms: tuple[Form, ...] | list[Form], title: str = "") -> Any:
    """A matplotlib Figure of one to four forms side by side with the terms they differ in.

    Parameters
    ----------
    forms : sequence of Form
        One to four forms.
    title : str, default: ""
        A line above them (e.g. the comparison's name).

    Returns
    -------
    matplotlib.figure.Figure
        16 x 9 inches; save it with `savefig` or show it on a Qt canvas.
    """
    from matplotlib.figure import Figure  # matplotlib: only when a figure is asked for

    texts = compared_terms(forms)
    leaves = [form.leaf() for form in forms]
    figure = Figure(figsize=FIGURE_SIZE)
    if title:
        figure.suptitle(title, fontsize=TITLE_PT, y=0.97)
    # one scale for all: every panel shows the same span of the plane (upright: x is up)
    spans = np.array([np.ptp(leaf.boundary[:, :2], axis=0) for leaf in leaves])
    length, width = spans[:, 0].max() * 1.06, spans[:, 1].max() * 1.06
    grid = figure.add_gridspec(
        2, len(forms), height_ratios=(2.0, 1.0), top=0.9 if title else 0.97, bottom=0.02
    )
    column_inches = FIGURE_SIZE[0] / len(forms)
    chars = int(TEXT_SHARE * column_inches * 72 / (CHAR_WIDTH * TEXT_PT))
    for column, (leaf, terms) in enumerate(zip(leaves, texts, strict=True)):
        ax = figure.add_subplot(grid[0, column])
        xy = leaf.boundary[:, :2]
        draw_outline(ax, xy, [v[:, :2] for v in leaf.veins])
        middle = (xy.min(axis=0) + xy.max(axis=0)) / 2
        ax.set_xlim(-middle[1] - width / 2, -middle[1] + width / 2)
        ax.set_ylim(middle[0] - length / 2, middle[0] + length / 2)
        name_pt = TITLE_PT if len(forms) <= 3 else TITLE_PT - 4  # four names in a row
        _write_terms(figure.add_subplot(grid[1, column]), terms, chars, name_pt)
    return figure
