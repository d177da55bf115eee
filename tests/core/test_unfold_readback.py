"""Posed forms written to a point list (a CSV keeps no pose) and opened again read back their
flat blade's size and their own pose (issue 21, item 2; core/unfold.py). Session 37 measured
these off (/work/notes/pose37/repro.py): each test fails on the code before its fix."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from leafstudio.core.pipeline import Pipeline
from leafstudio.forms.make import Form
from leafstudio.model import Params


def _read_back(tmp_path, shape: str, terms: dict):
    """The leaf `Form(shape, **terms)` opens as from its CSV (workflows.open_file), and the form's
    own pose (bend.Pose)."""
    from leafstudio.sources.files import save_leaf
    from leafstudio.workflows import open_file

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a strong bend warns of the side view
        posed = Form(shape, **terms).leaf()
        path = tmp_path / "posed.csv"
        save_leaf(posed, path)  # as `leafstudio form ... -o posed.csv` writes it
        return open_file(str(path)).leaf, posed.bend


def _assert_flat_size(leaf, shape: str, terms: dict) -> None:
    """`leaf`'s flat blade, in its fitted frame, as long and wide as the flat form's (1%)."""
    bend = leaf.bend
    assert bend is not None
    flat = bend.frame.to_plane(bend.flat_curve(leaf.boundary, ring=True))[0]
    flat_terms = {k: v for k, v in terms.items() if k not in ("fold", "curl", "roll", "twist")}
    own = np.ptp(Form(shape, **flat_terms).leaf().boundary[:, :2], axis=0)
    assert np.ptp(flat, axis=0) == pytest.approx(own, rel=0.01)


@pytest.mark.parametrize(
    ("shape", "terms"),
    [
        ("ovate", {"margin": "serrate", "curl": 0.5, "roll": 0.3}),
        ("ovate", {"curl": 0.3, "roll": 0.2}),
        ("ovate", {"fold": 10.0}),
    ],
    ids=str,
)
def test_a_bowl_curled_and_rolled_up_reads_back_its_pose(tmp_path, shape, terms):
    """Curled and rolled up, a blade is a bowl whose midrib does not sink under its rim (1.02
    times its shadow, unfold_checks.FORESHORTENED) and whose margin is 0.09-0.10 of its width off
    its plane, under OFF_PLANE's 0.12: no pose was fitted, and it ran as a height field (serrate
    ovate curled 0.5 and rolled 0.3 3.4% narrow; ovate curled 0.3 and rolled 0.2 2.4% wide,
    folded 10 2.8% wide). At 0.06 each is fitted its own pose (the app keeps a cup's refusal for
    its edits: test_unfold_in_app)."""
    leaf, own = _read_back(tmp_path, shape, terms)
    _assert_flat_size(leaf, shape, terms)
    pose = leaf.bend.pose
    assert pose.fold == pytest.approx(own.fold, abs=0.1)
    assert (pose.curl, pose.roll) == pytest.approx((own.curl, own.roll), rel=0.01, abs=1e-6)


def test_a_tube_reads_back_its_width(tmp_path):
    """Linear rolled 1 (a tube) stopped reading its sheet at the third round, the rms still
    falling 8% a round (unfold.SHEET_STALL 0.9): roll 86.99 of the form's 87.96, 1.1% wide.
    The best of the rounds while the rms falls 1% a round: 87.39, 0.7% wide."""
    leaf, own = _read_back(tmp_path, "linear", {"roll": 1.0})
    _assert_flat_size(leaf, "linear", {})
    assert leaf.bend.pose.roll == pytest.approx(own.roll, rel=0.01)


@pytest.mark.xfail(strict=True, reason="not fixed in session 37: /work/notes/pose37/REPORT.md")
@pytest.mark.parametrize(
    ("shape", "terms"),
    [
        # the waves stay on the flat blade, which no pose in unfold.py lays flat: mixed's best
        # leaves 1.27e-2 of the length off flat (fold 45.5), 0.42 of the quadric's rms; none
        # fitted, 6.9% wide as a height field
        ("ovate", {"fold": 45.0, "wave": 0.1}),
        # a bowl whose rim lies on a plane (the quadric leaves 3.7e-4 of the length): a curl of
        # -0.92 and roll of -1.10 about the margin's plane lays it within 2.0e-5, 20% short
        ("orbicular", {"curl": -1.0, "roll": -0.3}),
        # a fold with a roll: refolded's rounds settle at fold 46.6 and roll 14.68 (the form's
        # 45 and 14.14), 1.2% wide; unfold_mixed from there drifts to fold 46.8, roll 13.06
        ("lanceolate", {"fold": 45.0, "roll": 0.5}),
    ],
    ids=str,
)
def test_a_posed_form_read_back_from_a_csv_has_its_size_and_pose(tmp_path, shape, terms):
    """Session 37's other three: each read back off its flat size or its pose (repro.py)."""
    leaf, own = _read_back(tmp_path, shape, terms)
    _assert_flat_size(leaf, shape, terms)
    pose = leaf.bend.pose
    assert pose.fold == pytest.approx(own.fold, abs=0.5)
    assert (pose.curl, pose.roll) == pytest.approx((own.curl, own.roll), rel=0.01, abs=1e-6)


@pytest.mark.parametrize(
    ("terms", "size"),
    [
        # fitted fold 60.6, twist 0.623 (the form's 0.628); veins up to 5.1e-4 of the length
        # off the mesh (the .leaf.json's 5.2e-4), no veins meeting at different heights
        ({"fold": 60.0, "twist": 0.2}, 0.01),
        # none was fitted (71% narrow as a height field); now fold 60.6, curl 0.534, roll 3.27
        # (the form's 60, 0.5, 3.02), 1.1% wide, veins within 5.6e-4 of the mesh (2.0e-2 before)
        ({"fold": 60.0, "curl": 0.5, "roll": 0.3}, 0.02),
    ],
    ids=str,
)
def test_a_fold_of_60_with_more_reads_back_its_pose(tmp_path, terms, size):
    """Ovate folded 60 and twisted 0.2, or curled and rolled: every fit about the margin's plane
    went to a fold of 26-32 and a curl of -1 (the plane's shear), unfold_mixed's relief rounds
    stalled there (4.2e-3 of the length off flat) and none was fitted: as a height field its
    veins met at different heights in 11-13 places and stood up to 7.9e-3-2.0e-2 of the length
    off the mesh. unfold_mixed now starts its rounds from a fold of 60 too (FOLDED), and keeps
    what swings within MIXED_KEPT of flat (/work/notes/pose38)."""
    leaf, own = _read_back(tmp_path, "ovate", terms)
    assert leaf.bend is not None
    flat = leaf.bend.frame.to_plane(leaf.bend.flat_curve(leaf.boundary, ring=True))[0]
    own_size = np.ptp(Form("ovate").leaf().boundary[:, :2], axis=0)
    assert np.ptp(flat, axis=0) == pytest.approx(own_size, rel=size)
    pose = leaf.bend.pose
    assert abs(pose.fold) == pytest.approx(own.fold, abs=1.0)
    assert abs(pose.twist) == pytest.approx(own.twist, rel=0.03, abs=1e-6)


@pytest.mark.parametrize(
    ("shape", "terms"),
    [
        # fitted fold -31.1, curl 1.08: 0.60 wide, 0.51 of the area (/work/notes/wrongpose38)
        ("ovate", {"fold": 75.0, "twist": 0.2}),
        ("ovate", {"fold": 70.0, "twist": 0.2}),  # none fitted: 0.61 wide as a height field
        ("elliptic", {"fold": 75.0, "twist": 0.2}),  # a curl of 1.49 alone: 0.49 wide
    ],
    ids=str,
)
def test_a_fold_of_70_to_75_twisted_reads_back_its_pose(tmp_path, shape, terms):
    """Folded 70-75 and twisted 0.2: unfold_mixed's rounds, each relief read as the pose before
    laid the curves flat about the relief before, swung off the form's own pose (its exact
    fixed point) from a start 0.01 rad off it and stalled 7e-4 of the length off flat, over
    MIXED_KEPT, so unfold.py's wrong fit stood. unfold_mixed's bare rounds reach the form's
    own pose (/work/notes/pose39)."""
    import shapely

    leaf, own = _read_back(tmp_path, shape, terms)
    _assert_flat_size(leaf, shape, terms)
    pose = leaf.bend.pose
    assert pose.fold == pytest.approx(own.fold, abs=1.0)
    assert pose.twist == pytest.approx(own.twist, abs=0.02)
    assert (pose.curl, pose.roll) == pytest.approx((0.0, 0.0), abs=0.02)
    flat = leaf.bend.frame.to_plane(leaf.bend.flat_curve(leaf.boundary, ring=True))[0]
    area = shapely.Polygon(Form(shape).leaf().boundary[:, :2]).area
    assert shapely.Polygon(flat).area == pytest.approx(area, rel=0.01)


@pytest.mark.parametrize("wrong", [True, False], ids=["a wrong pose", "its own"])
def test_a_pose_that_leaves_the_margin_off_flat_is_warned_of(tmp_path, wrong):
    """A pose fitted to 3D curves that leaves the margin farther off flat than
    unfolded.OFF_FLAT is read unreliably: opening the file says so. Ovate folded 75 and
    twisted 0.2 was fitted fold -31.1 and curl 1.08 (the margin 1.46e-2 of the diagonal off
    flat, the flat blade 0.633 wide, and no word of it: /work/notes/wrongpose38); it reads its
    own pose now (the test above), whose fold set 5° off leaves the margin 1.72e-2 of the
    diagonal off flat (/work/notes/pose39/wrong_pose.py)."""
    from dataclasses import replace

    from leafstudio.model import Leaf
    from leafstudio.sources.files import save_leaf
    from leafstudio.workflows import open_file

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        posed = Form("ovate", fold=75.0, twist=0.2).leaf()
    path = tmp_path / "posed.csv"
    save_leaf(posed, path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        leaf = open_file(str(path)).leaf
    if wrong:
        bend = leaf.bend
        pose = replace(bend.pose, fold=bend.pose.fold - 5.0)
        leaf = Leaf(leaf.boundary, leaf.veins, bend=replace(bend, pose=pose))
    # said in the result's warnings, which the commands and the window say (a warning from
    # the fit alone went unseen: the command line ignores warnings)
    result = Pipeline(leaf).run(Params(k=2, grid=32))
    said = [note for note in result.warnings if "could not be read reliably" in note]
    assert bool(said) == wrong
    if wrong:
        assert "distorted" in said[0]
