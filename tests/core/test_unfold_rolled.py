"""A form folded and rolled the same way, saved as its curves without its pose, is laid out at
its own size (core/unfold_rolled.py): the fit about the midrib's hinge eased its fold by the
POSED margin's half width and rolled it about the margin's plane, and came back too wide or in
another pose (saved as CSVs and read back: oblong folded 45 and rolled 0.5 36% too wide,
lanceolate so posed fitted a fold of -9.4 and a roll of -23, 25% too narrow)."""

from __future__ import annotations

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.core.bend import flat_leaf
from leafstudio.core.unfold import fit_pose
from leafstudio.forms.make import Form


@pytest.mark.parametrize("shape", ["oblong", "lanceolate"])
def test_a_form_folded_and_rolled_without_its_pose_is_laid_out_at_its_own_width(shape):
    """Fitted straight from the curves (no CSV's round-off): oblong came out 1.362 times its
    flat width (fold 55.1), lanceolate 0.749 (fold -9.4); now 1.000 and 1.012 (fold 44.8, 46.6)."""
    leaf = Form(shape, fold=45.0, roll=0.5).leaf()
    bend = fit_pose(ls.Leaf(leaf.boundary, leaf.veins))
    assert bend is not None
    assert bend.pose.fold == pytest.approx(45.0, abs=4.0)
    flat = flat_leaf(ls.Leaf(leaf.boundary, leaf.veins, bend=bend))
    across = bend.frame.to_plane(flat.boundary)[0][:, 1]
    own = flat_leaf(leaf).boundary[:, 1]
    assert np.ptp(across) == pytest.approx(np.ptp(own), rel=0.02)
