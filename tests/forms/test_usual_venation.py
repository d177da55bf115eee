"""Each shape's usual venation, as its usual apex and base (forms/terms.ShapeSpec.venation),
and its usual count of secondaries (ShapeSpec.secondaries).

Issue 21 measures a form's mesh against the form's own surface. A reniform form was veined as
every shape was, pinnately: its secondaries ran from the midrib to the far margin and none
into the two basal lobes, whose surface no vein told the method about. There its mesh stood
0.0036 of the length off its own surface (95th percentile, K 3, grid 128). Reniform leaves
(Asarum, Caltha, Pelargonium) are palmate: their main veins spread from the stalk into both
lobes, and a class shown "reniform" should see that.

Deltoid and spatulate forms stood 0.0035 off their own surfaces the same way: six secondaries a
side left the deltoid's basal corners and the spatulate's broad apex without a vein. Deltoid
birches carry 6 to 12 pairs (B. ermanii, truncate at the base as our deltoid: 10 to 12); the
forms now carry 10 and 8.
"""

from __future__ import annotations

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.forms import Form
from leafstudio.forms.own_surface import own_heights
from leafstudio.forms.terms import SHAPES


def test_a_shape_names_its_usual_venation_and_a_form_may_name_another():
    assert Form("reniform").venation_term == "palmate"
    assert Form("reniform", venation="pinnate").venation_term == "pinnate"
    assert Form("ovate").venation is None and Form("ovate").venation_term == "pinnate"
    assert {spec.venation for spec in SHAPES.values()} == {"pinnate", "palmate"}
    again = Form(**Form("reniform").to_dict())  # a saved form keeps the shape's usual
    assert again.venation_term == "palmate"
    assert Form(**Form("reniform", venation="pinnate").to_dict()).venation_term == "pinnate"


@pytest.mark.parametrize(("venation", "into_lobes"), [(None, True), ("pinnate", False)])
def test_a_reniform_forms_veins_reach_both_lobes(venation, into_lobes):
    """The lobes lie beside the notch at the base (x < 0.3 of the length): a palmate form's
    main veins end there on both sides; a pinnate one's secondaries all end past x = 0.5."""
    leaf = Form("reniform", venation=venation).leaf()
    ends = np.array([vein[-1] for vein in leaf.veins[1:]])
    in_lobe = ends[:, 0] < 0.3
    both = bool(np.any(in_lobe & (ends[:, 1] > 0)) and np.any(in_lobe & (ends[:, 1] < 0)))
    assert both == into_lobes


@pytest.mark.parametrize("shape", ["reniform", "ovate", "hastate"])
def test_a_forms_own_surface_holds_its_veins(shape):
    """own_heights is the surface the form's veins were lifted onto (forms/veins.grow_veins):
    every vein point within 1e-9 of the length of it, so a mesh measured against it is
    measured against the form."""
    form = Form(shape)
    veins = np.vstack(form.leaf().veins)
    assert np.abs(own_heights(form)(veins) - veins[:, 2]).max() <= 1e-9


def test_a_shape_names_its_usual_secondaries_for_its_usual_venation_only():
    assert Form("deltoid").secondaries_count == 10
    assert Form("spatulate").secondaries_count == 8
    assert Form("ovate").secondaries_count is None  # the venation's default, 6
    assert Form("deltoid", secondaries=4).secondaries_count == 4
    assert Form("deltoid", venation="palmate").secondaries_count is None
    sides = [len(Form(shape).leaf().veins) - 1 for shape in ("ovate", "deltoid", "spatulate")]
    assert sides[1] > sides[0] + 4 and sides[2] > sides[0] + 2  # a secondary cut short drops


@pytest.mark.parametrize("shape", ["reniform", "deltoid", "spatulate"])
def test_a_forms_mesh_lies_on_its_own_surface(shape):
    """95th-percentile distance from the mesh to the form's own surface within 2e-3 of the
    length (issue 21); with every shape pinnate with 6 secondaries a side: reniform 3.6e-3,
    deltoid and spatulate 3.5e-3."""
    form = Form(shape)
    result = ls.reconstruct(form.leaf(), ls.Params(k=3, grid=128))
    points = np.asarray(result.triangle_mesh.points)
    off = np.abs(points[:, 2] - own_heights(form)(points)) / result.length
    assert np.percentile(off, 95) <= 2e-3
