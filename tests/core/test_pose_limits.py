"""A pose past what it keeps of the blade is refused wherever it enters (core/pose_limits.py):
before, only a project's "bend" was (sources/bend_entry.py); `Pose(fold=89)` given through the
API was taken and kept 0.83 of the blade's area, silently (closing31, "Noticed and left alone")."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.core.bend import Pose, flat_leaf
from leafstudio.core.placed import PlacedPose
from leafstudio.core.pose_limits import pose_trouble
from leafstudio.core.pose_relief import relief_of
from leafstudio.forms import Form
from leafstudio.model import Leaf


@pytest.fixture(scope="module")
def blade() -> Leaf:
    return Form("ovate").blade()


def _posed(blade: Leaf, pose: Pose) -> Leaf:
    """`blade` bent by `pose` as the API bends one (and exports31's scripts did)."""
    return Leaf(pose.apply(blade.boundary), [pose.apply(v) for v in blade.veins], bend=pose)


def _terms(blade: Leaf) -> dict[str, dict[str, float]]:
    """Past each limit, in the pose's units (a roll of 1.2 half turns at the widest margin, a
    twist of 3 half turns of the apex)."""
    half = float(np.abs(blade.boundary[:, 1]).max())
    return {
        "fold 89": {"fold": 89.0},  # 0.83 of the area (appreview31, s15)
        "fold -85": {"fold": -85.0},  # 1.10
        "curl 2": {"curl": 2.0},  # the midrib turned 4 radians, past half a turn
        "roll 1.2": {"roll": 1.2 * np.pi / half},  # past the closed tube
        "twist 3": {"twist": 3 * np.pi},
    }


@pytest.mark.parametrize("name", ["fold 89", "fold -85", "curl 2", "roll 1.2", "twist 3"])
def test_a_leaf_posed_past_the_limits_through_the_api_is_refused_by_name(blade, name):
    terms = _terms(blade)[name]
    pose = Pose(**terms, relief=relief_of(blade.boundary, blade.veins))
    leaf = _posed(blade, pose)
    term = next(iter(terms))
    for call in (lambda: ls.reconstruct(leaf, ls.Params(k=3, grid=32)), lambda: ls.Pipeline(leaf)):
        with pytest.raises(ls.LeafError) as raised:
            call()
        message = str(raised.value)
        assert f'"{term}" {getattr(pose, term):g}' in message, message
        assert " to " in message and "\n" not in message  # the range allowed, one line


def test_a_pose_within_the_limits_still_reconstructs(blade):
    """The sliders' ends, every term at once, and a pose with no relief at them (an older
    project's) are taken."""
    for leaf in (
        Form("ovate", fold=75, curl=1, roll=1, twist=1).leaf(),
        _posed(blade, Pose(-75.0, -1.0, -np.pi / float(np.abs(blade.boundary[:, 1]).max()))),
    ):
        assert ls.Pipeline(leaf).leaf.bend is leaf.bend


def test_a_fitted_pose_keeps_its_wider_fold():
    """A pose fitted to curves in 3D (core/unfold.py) was searched to pose_limits.FITTED_FOLD
    (85°): the pipeline takes it there, as the loader does; a form's pose at 83° is refused."""
    from leafstudio.core.unfold import fit_pose

    form = Form("ovate", fold=75.0).leaf()
    fit = fit_pose(Leaf(form.boundary, form.veins))
    assert fit is not None and fit.pose.relief.on_margin
    flat = flat_leaf(Leaf(form.boundary, form.veins, bend=fit))
    bend = PlacedPose(replace(fit.pose, fold=83.0), fit.frame)
    ls.Pipeline(Leaf(bend.apply(flat.boundary), [bend.apply(v) for v in flat.veins], bend=bend))
    blade = Form("ovate").blade()
    with pytest.raises(ls.LeafError, match='"fold" 83'):
        ls.Pipeline(_posed(blade, Pose(fold=83.0, relief=relief_of(blade.boundary, blade.veins))))


def test_a_roll_past_the_tube_without_a_relief_is_seen_on_the_flat_blade(blade):
    """Bent, a pose without a relief lays its margins on the tube's seam (no point turns past
    half a turn) and reads as exactly a tube: its bent curves cannot tell a roll of 1.2 from a
    narrower blade's 1.0. Where a pose meets the flat blade (the app's sliders), the flat
    blade is measured: 1.2 half turns, refused."""
    half = float(np.abs(blade.boundary[:, 1]).max())
    pose = Pose(roll=1.2 * np.pi / half)
    leaf = _posed(blade, pose)
    assert pose_trouble(pose, leaf.boundary, list(leaf.veins)) is None  # what the loader sees
    said = pose_trouble(pose, blade.boundary, list(blade.veins), flat=True)
    assert said is not None and "1.2 half turns" in said
    assert pose_trouble(replace(pose, roll=np.pi / half), blade.boundary, blade.veins, True) is None


def test_a_project_posed_past_the_limits_is_not_written(blade, tmp_path):
    """`ls.save_leaf` wrote a project its loader then refused (sources/bend_entry.py)."""
    leaf = _posed(blade, Pose(fold=89.0, relief=relief_of(blade.boundary, blade.veins)))
    path = tmp_path / "f.leaf.json"
    with pytest.raises(ls.LeafError, match=r'f\.leaf\.json: .*"fold" 89'):
        ls.save_leaf(leaf, path)
    assert not path.exists()


@pytest.mark.parametrize("turn", [1.005, 1.01])
def test_a_roll_past_the_tube_is_refused_not_laid_on_its_seam(turn):
    """Pose.apply turns no point past half a turn, but the limit took rolls to 1.01 half
    turns: the margins past the tube were laid on its seam without a word (a linear blade
    rolled 1.01 kept 0.988 of its area, 0.998 as a tube). A roll asked for (the app's, on the
    flat blade) is taken to the tube; the sliders' own tube still is
    (test_a_pose_within_the_limits_still_reconstructs)."""
    blade = Form("linear").blade()
    half = float(np.abs(blade.boundary[:, 1]).max())
    relief = relief_of(blade.boundary, blade.veins)
    asked = Pose(roll=turn * np.pi / half, relief=relief)
    said = pose_trouble(asked, blade.boundary, list(blade.veins), flat=True)
    assert said is not None and f"{turn:.4g} half turns" in said
    assert "up to 1 (a closed tube)" in said
    tube = _posed(blade, Pose(roll=np.pi / half, relief=relief))
    assert pose_trouble(tube.bend, tube.boundary, list(tube.veins)) is None


def test_a_tube_the_app_saved_widened_by_a_sketch_edit_still_opens(tmp_path):
    """The app kept a tube's roll when a sketch edit widened the blade by under 1% (eased_roll
    eased only past the old limit, 1.01), and saved it so: tube_widened_18cfd45.leaf.json, the
    Roll slider's tube with its widest point moved 0.5% out, saved by 18cfd45's app, rolls its
    margins 1.005 half turns, and the tube as the limit refused it ("through 1 half turns; a
    roll is taken up to 1"). A leaf's pose as given is taken to 1.01; past that, refused."""
    path = Path(__file__).resolve().parents[1] / "data" / "tube_widened_18cfd45.leaf.json"
    leaf = ls.load_leaf(path)
    assert leaf.bend is not None
    pose = leaf.bend.pose
    wider = replace(leaf.bend, pose=replace(pose, roll=pose.roll * 1.02))
    said = pose_trouble(wider, wider.apply(flat_leaf(leaf).boundary), [])
    assert said is not None and "up to 1.01 (a closed tube, widened by a sketch edit)" in said


def test_a_roll_at_the_seam_through_the_sliders_units_is_not_said_eased():
    """The sliders' roll of 0.99 (folded) comes back from the pose's units (π over the half
    width: gui/model/bending.term_units) 1 ulp over at 257 of 2000 half widths
    (/work/notes/review38): it is at the seam, not eased past it, so `seam_note` says nothing
    of it; 1 is said eased."""
    from leafstudio.core.pose_limits import SEAM_SHARE, seam_note

    for half in np.random.default_rng(0).uniform(0.05, 1.0, 200):
        unit = np.pi / half
        assert seam_note(SEAM_SHARE * unit / unit, 30.0, 0.0) == ""
    assert "eased to 0.99" in seam_note(1.0, 30.0, 0.0)
