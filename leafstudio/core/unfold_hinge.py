"""The reliefs a pose fitted to curves in 3D bends about (core/unfold.py): the midrib's hinge as
the pose lays it flat (`hinge_relief`), the margin's rise and fall off it (`fallen_slopes`) and the
share of the turn the fold takes about them (`turn_share`).

Those fits fold about the margin's plane, which shears each half, and a roll made up for it: an
ovate folded 60° and saved without its pose was fitted fold 61, curl 0.10 and roll -0.54, whose
flat blade was 43% too large (`leafstudio measure` read it 0.935 wide, with its pose 0.625).
Once a leaf is to be unfolded, each fit is fitted again with a relief whose hinge is the midrib
as the pose lays it flat (`hinge_relief`), so the fold turns each half rigidly about the midrib as a
form's does (that ovate: fold 59.998, curl 0, roll 0, 0.625 wide), and kept where it lays the
margin clearly flatter (HINGE_GAIN). Whether to unfold is asked of those only where the fits
about the margin's plane fall short, and far more strictly (HINGE_EXPLAINED): a fold about the
midrib's own heights also lays a waved blade's margin flatter (0.19-0.52 of the quadric's rms).
They fall short on a domed blade folded with its lobes behind the base or folded down: a fold
about the margin's plane shears it, and a roll makes up for less of that (sagittate folded 60
left 0.31 of the quadric's rms, cordate 0.21 and its simplest fit more, ovate folded -60 0.66,
all refused: sagittate measured 0.248 wide against its flat 0.407); the hinge leaves 0.001-0.007.
A form's dome falls 12-14° from its hinge, and folded hard down the form eases its halves' turn
(hinge_fold.fold_share); a fit about a hinge turned rigidly was off (ovate folded -75: fitted
-72.2, 1.043 times its flat width). The fit about the hinge is done again with the rise and
fall of the margin as that fit lays it flat (`fallen_slopes`), until the fold's share of the
turn they give stays (ovate: -75.03, 1.001).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from leafstudio.core.bend import Pose
from leafstudio.core.hinge_fold import fold_share
from leafstudio.core.pose_relief import Relief, margin_relief, margin_slopes, sheet_relief

HINGE_ROUNDS = 6  # rounds that find a curled midrib's flat heights (hinge_relief): at ovate
# folded 75 and curled 1's own pose the curl's level went 0.021, 0.031, 0.036 and, in five,
# 0.0405 (its form's 0.0403; ten to forty: 0.042); saved as a CSV, it was fitted fold 74.7 and
# curl 0.986 in 3 rounds (0.4% long), 74.9 and 1.000 in 6 (0.1%)
ROLLED_ROUNDS = 3  # ... and with a roll, read with the fold as before (hinge_relief): in 6, oblong
# folded 45 and rolled 0.5, saved as a CSV, came back 0.2% narrow where it was 0.0%
FALL_ROUNDS = (
    6  # rounds that find the flat margin's rise and fall off the hinge (fallen_slopes): on
)
# ovate folded -75 at its own pose the fall read 13.36, 13.94, 14.04 and 14.05° (the form's 14.06)
SHARE_CLOSE = 1e-4  # ... until the fold's share of the turn moves less than this (0.002° of fall
# at a fold of 75°)


def hinge_relief(
    pose: Pose,
    midrib: np.ndarray,
    boundary: np.ndarray,
    slopes: tuple[float, float] = (0.0, 0.0),
    sheet: tuple[tuple[float, ...], tuple[float, ...]] | None = None,
) -> Relief | None:
    """A relief for `pose` (without one) whose hinge is the (m, 3) `midrib`, in the blade's
    frame, as the pose lays it flat, its sheet the margin's plane (pose_relief.margin_relief)
    and its rise and fall `slopes` (radians; 0: each half turned rigidly): the fold then turns
    each half about the midrib, as a form's does, where a pose without a relief sheared it (an
    ovate folded 60° and saved without its pose was fitted fold 61, curl 0.10 and roll -0.54,
    which laid its margin flat but its blade out 43% too large).
    A fold and a roll leave the midrib as it stands; the curl bends about the midrib's mean
    height as posed (Relief.posed_level), which the hinge's heights set: they are found in
    HINGE_ROUNDS rounds (ROLLED_ROUNDS with a roll), each flattening the midrib about the last
    round's (on ovate folded 45° and curled 0.5 the heights moved 2.3e-2, 4.9e-3 and 1.6e-3 of
    the length; about the margin's plane alone its own surface was 1.3e-3 off at p95, now
    2.1e-4). With a curl the
    midrib is flattened without the fold, which leaves a midrib on its hinge where it is:
    unfolded about the last round's hinge, a midrib point over or under it was turned toward a
    half and read back only part of its height, and at ovate folded 75 and curled 1's own pose
    the level went 0.021, 0.038, 0.013, 0.006 and -0.030 in 1, 2, 3, 5 and 10 rounds against
    the form's 0.040 (from its CSV it was fitted fold 74.4, curl 0.93 and roll -0.15: 1.7%
    long, 2.7% narrow; now 74.9, 1.000 and none, 0.1%). Not with a roll (unfold_rolled.py's
    fits, a fold and a roll with a curl or without): linear folded 75 and rolled 1 read so was
    fitted 1.7e-4 of the length off flat, 9.2e-5 as before, its glb's apex 1.70 degrees off +X
    (0.62), and oblong folded 60 and rolled 0.3 0.9% narrow (0.6). A roll fitted about its
    sections' own mean heights (`sheet`: knots and means, pose_relief.sheet_relief) keeps them,
    and flattens the midrib about them. None when the midrib doubles back."""
    relief = None if sheet is None else sheet_relief(*sheet)
    curled = pose.curl != 0 and pose.roll == 0  # a roll's: unfold_rolled's fits, as before
    fold = 0.0 if curled else pose.fold
    for _ in range(HINGE_ROUNDS if curled else ROLLED_ROUNDS if pose.curl != 0 else 1):
        # each round's `slopes` too: margin_relief reads them off `boundary` as if it lay
        # flat, and a hastate folded 75 went 600 steps astray (9.7 s) through a curl's rounds
        flat = replace(pose, fold=fold, relief=relief).flatten(midrib)
        relief = margin_relief(boundary, [flat], slopes)
        if relief is None:
            return None
        if sheet is not None:
            relief = replace(relief, knots=sheet[0], mean=sheet[1])
    return relief


def turn_share(pose: Pose, relief: Relief) -> float:
    """The share of the relief's turn `pose`'s fold takes about `relief` (bend.Pose)."""
    return fold_share(pose.fold, relief.fold_room(pose.fold, pose.roll)) if pose.fold else 1.0


def fallen_slopes(pose: Pose, boundary: np.ndarray) -> tuple[float, float]:
    """The rise and the fall (radians) of the (n, 3) `boundary`, in the blade's frame, off
    `pose`'s relief's hinge as `pose` lays it flat (pose_relief.margin_slopes), in FALL_ROUNDS
    rounds, each flattening about the last round's: they ease the fold's turn
    (hinge_fold.fold_share), which sets where the margin lies flat. A round that leaves the
    share of the turn as it was is the last: a fold of up to 60° turns a form's dome rigidly."""
    relief = pose.relief
    for _ in range(FALL_ROUNDS):
        rise, fall = margin_slopes(relief, replace(pose, relief=relief).flatten(boundary))
        fallen = relief.sloped(rise, fall)
        same = abs(turn_share(pose, fallen) - turn_share(pose, relief)) <= SHARE_CLOSE
        relief = fallen
        if same:
            break
    return relief.rise, relief.fall
