"""A traced outline is not searched for a surface (plausibility.is_outline): the search was half
the frame stage's time on every run, and an outline cannot cover a surface."""

from __future__ import annotations

import numpy as np
import pytest

from leafstudio.core.prepare.plausibility import check_not_a_surface, is_outline
from leafstudio.errors import LeafError
from leafstudio.forms import Form
from leafstudio.forms.terms import SHAPES


@pytest.mark.parametrize("shape", list(SHAPES))
@pytest.mark.parametrize("margin", ["entire", "dentate", "lobed"])
def test_every_forms_boundary_is_an_outline(shape, margin):
    assert is_outline(Form(shape, margin=margin).leaf().boundary)


def _rows(count: int, length: int = 100) -> np.ndarray:
    """Points in `count` rows, traced back and forth (row by row, alternately reversed)."""
    rows = [np.column_stack([np.arange(length), np.full(length, r), np.zeros(length)])
            for r in range(count)]  # fmt: skip
    return np.vstack([row if r % 2 == 0 else row[::-1] for r, row in enumerate(rows)]) * 0.01


def test_points_covering_an_area_are_no_outline_in_any_order():
    four = _rows(4)  # a closed path through four rows: the narrowest area one can cover
    assert np.linalg.norm(four[-1] - four[0]) < 0.08  # ... and it closes (JUMP steps)
    assert not is_outline(four)
    raster = _rows(40, 40)  # a scan's raster, in the scanner's order
    assert not is_outline(raster)
    with pytest.raises(LeafError, match=r"cover a surface|fill an area"):
        check_not_a_surface(raster)
    outline = Form("ovate").leaf().boundary
    shuffled = outline[np.random.default_rng(0).permutation(len(outline))]
    assert not is_outline(shuffled) and not is_outline(outline[:40])
