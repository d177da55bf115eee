"""The view aids' decisions (gui/model/view_aids.py): K's label on a blade with no relief of its
own (appreview31, finding 8) and no stretch of a posed leaf's view (finding 4)."""

from __future__ import annotations

import numpy as np

from leafstudio.core.bend import Pose
from leafstudio.core.pipeline import Pipeline
from leafstudio.forms import Form
from leafstudio.gui.model.view_aids import FLAT_K, k_label, stretches
from leafstudio.model import Leaf
from leafstudio.sources.demos import demo
from tests.gui.builders import FAST


def test_k_reads_unused_on_a_flat_blade_bent_or_not_and_the_mixtures_k_otherwise():
    """A blade whose veins lie in its plane fits no mixture: the view said "K = 1" beside a K
    slider at 3, bent or not."""
    t = np.linspace(0, 2 * np.pi, 80, endpoint=False)
    boundary = np.column_stack([0.5 + 0.5 * np.cos(t), 0.2 * np.sin(t), 0 * t])
    midrib = np.column_stack([np.linspace(0.02, 0.98, 12), np.zeros(12), np.zeros(12)])
    pose = Pose(curl=0.8)
    for leaf in (
        Leaf(boundary, [midrib]),
        Leaf(pose.apply(boundary), [pose.apply(midrib)], bend=pose),
    ):
        result = Pipeline(leaf).run(FAST)
        assert result.chosen_k == 1 and k_label(result) == FLAT_K
    assert k_label(Pipeline(demo("nested")).run(FAST)) == "K = 3"


def test_a_posed_leafs_view_is_not_stretched_a_flat_or_domed_ones_is():
    """Ovate curled 1 stretched 3 times along its flat blade's normal drew its midrib 2.37 long
    instead of 0.99: the stretch is off for a posed leaf."""
    assert not stretches(Pipeline(Form("ovate", curl=1.0).leaf()).run(FAST))
    assert stretches(Pipeline(Form("ovate").leaf()).run(FAST))


def test_a_scans_sheet_bent_view_is_not_stretched_either():
    """A scan bent by its sheet (sheet_bend.Scaled) carries its curve along its flat blade's
    normal as a pose does: soybean pot1_15's flat normal is 36° off its own plane and the blade
    stands 26 mm along it, 31 mm long. Stretched, the curve grew, not the relief. Here a blade
    rolled past the vertical."""
    from leafstudio.core.sheet import fit_sheet
    from leafstudio.core.sheet_bend import Scaled
    from tests.core.test_sheet import _blade, rolled

    bend = Scaled(fit_sheet(rolled(_blade(3000)), np.array([0.0, 0.0, 1.0]), 1.0), np.zeros(3), 1.0)
    t = np.linspace(0, 2 * np.pi, 120, endpoint=False)
    outline = np.column_stack([0.45 * np.cos(t), 0.18 * np.sin(t), np.zeros_like(t)])
    x = np.linspace(-0.4, 0.4, 20)
    midrib = np.column_stack([x, np.zeros_like(x), np.full_like(x, 0.01)])
    leaf = Leaf(bend.bent(outline), [bend.bent(midrib)], bend=bend)
    result = Pipeline(leaf).run(FAST)
    normal = np.asarray(result.frame.normal)
    points = np.asarray(result.triangle_mesh.points)
    assert np.ptp(points @ normal) > 0.1  # its roll stands along the normal, not a relief
    assert not stretches(result)


def test_the_measurements_panel_says_k_is_unused_on_a_flat_blade_not_1():
    """The view's corner said "K unused (flat blade)" while the Measurements panel's Leaf
    section said K 1 beside it (the flat blade's placeholder Gaussian); a relief's K is shown."""
    from leafstudio.gui.model.measurements import measurement_rows

    t = np.linspace(0, 2 * np.pi, 80, endpoint=False)
    boundary = np.column_stack([0.5 + 0.5 * np.cos(t), 0.2 * np.sin(t), 0 * t])
    midrib = np.column_stack([np.linspace(0.02, 0.98, 12), np.zeros(12), np.zeros(12)])

    def leaf_rows(leaf: Leaf) -> dict[str, str]:
        return dict(dict(measurement_rows(Pipeline(leaf).run(FAST)))["Leaf"])

    assert leaf_rows(Leaf(boundary, [midrib]))["K"] == "unused (flat blade)"
    assert leaf_rows(demo("nested"))["K"] == "3"


def test_the_laid_flat_layer_follows_the_layers_drawn_on_a_bent_leafs_flat_blade():
    """closing32: a bent leaf's g, p(x) and EM samples are drawn on its flat blade, and the
    layer laying the leaf flat under them was left off. It comes on with the first of them on
    a bent leaf and goes with the last, if it came on by itself; the user's own tick stays."""
    from leafstudio.gui.model.view_aids import BladeFollow

    follow, ticks = BladeFollow(), {"blade": False, "implicit": False, "em": False}
    assert follow.ticked({**ticks, "implicit": True}, bent=False, changed="implicit") is None
    ticks["implicit"] = True  # the leaf bent with g on: the result brings the blade
    assert follow.ticked(ticks, bent=True) is True
    ticks["blade"] = True
    ticks["em"] = True
    assert follow.ticked(ticks, bent=True, changed="em") is None
    ticks["implicit"] = False
    assert follow.ticked(ticks, bent=True, changed="implicit") is None  # EM still shows
    ticks["em"] = False
    assert follow.ticked(ticks, bent=True, changed="em") is False  # the last off: it goes
    ticks.update(blade=False, em=True)
    assert follow.ticked(ticks, bent=True, changed="em") is True
    ticks["blade"] = False  # the user takes it off: off while EM shows
    assert follow.ticked(ticks, bent=True, changed="blade") is None
    assert follow.ticked(ticks, bent=True) is None
    ticks.update(em=False)
    assert follow.ticked(ticks, bent=True, changed="em") is None
    ticks.update(blade=True)  # the user's tick, no field shown: kept when one comes and goes
    assert follow.ticked(ticks, bent=True, changed="blade") is None
    for on in (True, False):
        ticks["em"] = on
        assert follow.ticked(ticks, bent=True, changed="em") is None
    ticks.update(blade=False)
    follow.ticked(ticks, bent=True, changed="blade")
    ticks["em"] = True
    assert follow.ticked(ticks, bent=True, changed="em") is True
    ticks["blade"] = True  # unbent (a flat leaf opened): the blade it ticked goes
    assert follow.ticked(ticks, bent=False) is False
