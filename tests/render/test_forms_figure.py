"""Forms side by side on one figure, with their terms in words (the compare view and slides)."""

from __future__ import annotations

import itertools

from leafstudio.forms.glossary import COMPARISONS
from leafstudio.render.forms_figure import compare_figure


def _texts(figure) -> list[str]:
    return [t.get_text() for ax in figure.axes for t in ax.texts]


def test_four_margins_side_by_side_each_named_under_its_leaf():
    figure = compare_figure(COMPARISONS["four margins"], "four margins")
    leaves = [ax for ax in figure.axes if ax.patches]
    assert len(leaves) == 4
    lefts = [ax.get_position().x0 for ax in leaves]
    assert lefts == sorted(lefts)  # in the given order, left to right
    names = [t for t in _texts(figure) if t.endswith("margin")]
    assert names == ["entire margin", "serrate margin", "crenate margin", "lobed margin"]
    assert any("saw-toothed" in t for t in _texts(figure))


def test_the_forms_are_drawn_at_one_scale():
    figure = compare_figure(COMPARISONS["ovate beside obovate"])
    leaves = [ax for ax in figure.axes if ax.patches]
    spans = [
        (ax.get_xlim()[1] - ax.get_xlim()[0], ax.get_ylim()[1] - ax.get_ylim()[0]) for ax in leaves
    ]
    assert spans[0] == spans[1]


def test_four_definitions_side_by_side_keep_apart():
    """Four venations compared: 'five or more veins running' ended where 'secondary veins
    curving up' began (the 26-character lines filled 0.9 of their column at a mean character
    width, and these are wider than the mean). Each line keeps a gap to its neighbours'."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from leafstudio.forms import Form

    forms = [Form("ovate", venation=v) for v in ("pinnate", "palmate", "parallel", "arcuate")]
    figure = compare_figure(forms)
    renderer = FigureCanvasAgg(figure).get_renderer()
    columns = [
        [t.get_window_extent(renderer) for t in ax.texts]
        for ax in figure.axes
        if ax.texts and not ax.patches
    ]
    gap = 0.02 * figure.bbox.width / len(columns)
    for left, right in itertools.pairwise(columns):
        assert max(b.x1 for b in left) + gap < min(b.x0 for b in right)
