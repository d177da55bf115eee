"""A curled form saved as its curves without its pose is read back with its curl and at its own
size (core/unfold_curl.py, core/unfolded.levelled). Saved as CSVs and opened (issue 21, curl35):
reniform curled -1 was fitted nothing and came out 0.733 long, reniform curled 1 a roll of 1.78
in a frame turned across its midrib (1.126 long), ovate curled -0.8 a curl of -0.853 about the
margin's plane (0.938 long), ovate folded 75 and curled 1 fold 74.4, curl 0.93 and roll -0.15
(1.7% long, 2.7% narrow)."""

from __future__ import annotations

import numpy as np
import pytest

from leafstudio.core.bend import flat_leaf
from leafstudio.core.unfold import fit_pose
from leafstudio.core.unfolded import unfolded
from leafstudio.forms.make import Form
from leafstudio.model import Leaf
from leafstudio.sources.files import load_leaf, save_leaf


@pytest.mark.parametrize(
    ("shape", "curl"), [("reniform", -1.0), ("reniform", 1.0), ("ovate", -0.8)]
)
def test_a_curled_form_written_as_a_csv_reads_back_its_curl_and_size(tmp_path, shape, curl):
    form = Form(shape, curl=curl)
    path = tmp_path / "curled.csv"
    save_leaf(form.leaf(), path)  # 9 digits: the round-off a file brings
    opened = unfolded(load_leaf(path))
    assert opened.bend is not None
    pose = opened.bend.pose
    assert (pose.fold, pose.roll, pose.twist) == (0, 0, 0)
    assert pose.curl == pytest.approx(curl, rel=0.01)
    flat = opened.bend.frame.to_plane(flat_leaf(opened).boundary)[0]
    own = form.unposed().leaf().boundary[:, :2]
    assert np.ptp(flat, axis=0) == pytest.approx(np.ptp(own, axis=0), rel=0.01)


def test_a_form_folded_hard_and_curled_without_its_pose_is_laid_out_at_its_own_size():
    """Ovate folded 75 and curled 1: the curl's level, found in rounds that flattened the midrib
    about the last round's hinge with the fold, went astray (0.021, 0.038, 0.013 ... -0.030
    against the form's 0.040), and the fit took fold 74.4, curl 0.93 and roll -0.15, its flat
    blade 1.017 long and 0.607 wide against 1 by 0.625 (core/unfold_hinge.hinge_relief)."""
    form = Form("ovate", fold=75.0, curl=1.0)
    leaf = form.leaf()
    bend = fit_pose(Leaf(leaf.boundary, leaf.veins))
    assert bend is not None
    assert bend.pose.fold == pytest.approx(75.0, abs=0.5)
    assert bend.pose.curl == pytest.approx(1.0, rel=0.01)
    assert abs(bend.pose.roll) < 0.01
    flat = bend.frame.to_plane(flat_leaf(Leaf(leaf.boundary, leaf.veins, bend=bend)).boundary)[0]
    own = form.unposed().leaf().boundary[:, :2]
    assert np.ptp(flat, axis=0) == pytest.approx(np.ptp(own, axis=0), rel=0.01)
