"""A leaf opened as curves in 3D without a pose (issue 21, build item 2) is unfolded once, when
it opens: the app then shows its flat blade's sketch, its sliders show the fitted pose, and a
change of K reuses the pipeline. Before, the pipeline unfolded it out of the session's sight: the
sketch stayed on "Waiting for the leaf" and the sliders at 0."""

from __future__ import annotations

import numpy as np

from leafstudio.core.bend import Pose
from leafstudio.core.placed import PlacedPose
from leafstudio.forms import make_form
from leafstudio.model import Leaf
from leafstudio.sources.files import save_leaf

from .test_session_files import opened_session


def test_a_folded_leaf_without_its_pose_opens_unfolded_with_its_sketch_and_pose(tmp_path):
    form = make_form("ovate", fold=60.0)
    path = tmp_path / "folded.csv"
    save_leaf(Leaf(form.boundary, form.veins), path)  # its curves in 3D, no pose
    session, runner, got = opened_session()
    session.open_path(str(path))
    assert got["opened"] == [str(path)]
    assert isinstance(session.leaf.bend, PlacedPose)
    # within 1.5°: the fit folds about the margin's plane, the form about its midrib's hinge
    # (core/hinge_fold.py), and a little roll makes up the rest (61.0°, roll -0.5)
    assert abs(abs(session.pose.fold) - 60.0) < 1.5, session.pose
    runner.finish(session)
    assert session.result.leaf is session.leaf
    sketch = session.editable_sketch()
    assert sketch is not None
    # the sketch draws the flat blade: its outline spans the form's flat width, not the folded
    # one (the fold turns each half up about the midrib, 0.078 high: from above the folded
    # outline is cos 60° as wide, and twice the hinge's height times sin 60° more, 0.72)
    width = np.ptp(sketch.frame.to_plane(sketch.to_leaf().boundary)[0][:, 1])
    flat_width = np.ptp(make_form("ovate").boundary[:, 1])
    assert np.ptp(form.boundary[:, 1]) < 0.75 * flat_width
    assert width > 0.98 * flat_width
    # a slider move re-bends the same blade
    session.set_bend(Pose(fold=0.0))
    runner.finish(session)
    assert session.leaf.bend is None
    relief = np.ptp(session.result.frame.to_plane(session.result.triangle_mesh.points)[1])
    assert relief < 0.2 * flat_width, relief
