"""The terms drawn and the forms compared (issue 22, "What to build" 4): a picture per term made
from the forms, and the terms in which compared forms differ."""

from __future__ import annotations

import numpy as np
import pytest

from leafstudio.errors import LeafError
from leafstudio.forms import Form
from leafstudio.forms.glossary import COMPARISONS, PICTURED, compared_terms, term_picture


def _shown(picture) -> np.ndarray:
    """The outline's and the veins' points inside the picture's box."""
    x0, y0, x1, y1 = picture.box
    xy = np.vstack([picture.outline, *picture.veins])
    keep = (xy[:, 0] >= x0) & (xy[:, 0] <= x1) & (xy[:, 1] >= y0) & (xy[:, 1] <= y1)
    return xy[keep]


@pytest.mark.parametrize("kind", list(PICTURED))
def test_every_term_has_a_picture_that_differs_from_the_others_of_its_kind(kind):
    shown = [_shown(term_picture(kind, term)) for term in PICTURED[kind]]
    assert all(len(xy) > 10 for xy in shown)
    for i, a in enumerate(shown):
        for b in shown[i + 1 :]:
            assert len(a) != len(b) or not np.allclose(a, b)


def test_an_apex_picture_shows_the_tip_and_a_base_picture_the_foot():
    apex, base = term_picture("apex", "emarginate"), term_picture("base", "cordate")
    assert apex.box[0] > 0.5 and apex.box[2] >= 1.0
    assert base.box[0] < 0.0 < base.box[2] < 0.5  # the cordate lobes reach back past the base


def test_a_picture_is_made_once():
    assert term_picture("margin", "serrate") is term_picture("margin", "serrate")


def test_an_unknown_term_is_one_leaf_error():
    with pytest.raises(LeafError, match="unknown apex 'pointy'"):
        term_picture("apex", "pointy")


def test_compared_forms_are_told_by_the_terms_they_differ_in():
    ovate, obovate = compared_terms(COMPARISONS["ovate beside obovate"])
    assert [t[:2] for t in ovate] == [("shape", "ovate")]  # its usual apex and base go with it
    assert [t[:2] for t in obovate] == [("shape", "obovate")]
    assert "egg-shaped" in ovate[0][2]
    margins = compared_terms(COMPARISONS["four margins"])
    assert [terms[0][1] for terms in margins] == ["entire", "serrate", "crenate", "lobed"]
    chosen = compared_terms([Form("ovate", apex="acute"), Form("obovate", apex="rounded")])
    assert [t[0] for t in chosen[0]] == ["shape", "apex"]


def test_two_to_four_forms_are_compared():
    assert all(2 <= len(forms) <= 4 for forms in COMPARISONS.values())
    with pytest.raises(LeafError, match="one to four forms"):
        compared_terms([Form("ovate")] * 5)


@pytest.mark.parametrize("margin", ["serrate", "serrulate", "dentate", "crenate"])
def test_a_toothed_margins_picture_shows_its_teeth_at_the_glossarys_size(margin):
    """Help > Glossary draws each term in a PICTURE-pixel square: the teeth of a toothed margin
    must stand at least 3 pixels off the entire margin's edge there, or a class on a projector
    sees serrulate as entire (the blade's whole middle, 0.15-0.85 of its length, drew a
    serrulate margin's teeth 1.4 pixels deep)."""
    from leafstudio.gui.qt.glossary_view import PICTURE  # Qt: only for the picture's size

    picture, entire = term_picture("margin", margin), term_picture("margin", "entire")
    x0, y0, x1, y1 = picture.box
    scale = 0.9 * PICTURE / max(x1 - x0, y1 - y0)  # draw_plane's pixels per leaf length
    shown = _shown(picture)
    side = shown[shown[:, 1] > 0.5 * y1]  # the margin's points shown (not the midrib)
    edge = entire.outline[entire.outline[:, 1] > 0]
    edge = edge[np.argsort(edge[:, 0])]
    depth = np.ptp(side[:, 1] - np.interp(side[:, 0], edge[:, 0], edge[:, 1]))
    assert len(side) > 10
    assert depth * scale >= 3.0


def test_arcuate_is_defined_as_the_veins_it_grows_curving_up_without_joining():
    """Arcuate secondaries (a dogwood's) bow up toward the apex along inside the margin and fade
    without joining the next: eucamptodromous, not brochidodromous (joined in loops). The forms
    grow them so (each ends a few hundredths of the length from every other secondary), and
    the definition a class reads says the same (it said 'each looping toward the next
    (brochidodromous)')."""
    from shapely.geometry import LineString, Point

    from leafstudio.forms.terms import definition

    for shape in ("ovate", "elliptic"):
        veins = [v[:, :2] for v in Form(shape, venation="arcuate").leaf().veins]
        for i, vein in enumerate(veins[1:], 1):
            others = [LineString(w) for j, w in enumerate(veins) if j not in (0, i)]
            assert min(o.distance(Point(vein[-1])) for o in others) > 0.01
    words = definition("arcuate", "venation")
    assert "loop" not in words and "brochidodromous" not in words
    assert "eucamptodromous" in words
