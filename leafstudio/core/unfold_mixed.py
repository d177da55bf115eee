"""A pose of all four terms fitted to curves in 3D about a relief as a form's (core/unfold.py asks
it where its own fits fall short).

unfold.py's fits bend about reliefs of their own: about the margin's plane (no relief), about
the midrib's hinge with the margin's plane for a sheet (unfold_hinge.py), about the sections'
means for a roll alone (`sheeted`), and a fold and a roll of one sign about a form's relief
(unfold_rolled.py); and it fits a roll and a twist together in none of its subsets of terms. A
form bends each section about its own mean height whatever its pose, so a posed form whose
terms mix otherwise, saved as a CSV and read back (/work/notes/s35/extra_rows.py), was fitted
nothing or the wrong pose: ovate rolled 0.5 and twisted 0.5 came back 10.8% narrow, elliptic
rolled 0.4 and twisted 1 was refused (its outline crossing itself as given), ovate folded -45
and rolled 0.4 was fitted fold -38.3 (16.1% wide), cordate folded 45 and rolled -0.5 12.3%
narrow, obovate curled 0.5 and rolled 0.4 9.9%, ovate folded 30, curled 0.5, rolled 0.3 and
twisted 0.5 14.1%.

`mixed` fits the fold, curl, roll and twist together, first about the margin's plane from the
fits unfold.py made and from a roll and a twist of either sign (the frame turned back by the
twist at the blade's middle, where the boundary's plane sees it), then about the relief read
off the curves as the fit before laid them flat (pose_relief.relief_of, as a form reads its own
blade), in rounds until that relief stays. Its frame's origin moves along the midrib too: a
form twists and curls from its blade's base, which the midrib's first point is not (ovate
folded 30, curled 0.5, rolled 0.3 and twisted 0.5 stalled 2.2e-4 of the length off flat from
that point, its roll 4% short; from the base the form's own to 1e-5). Terms it finds near 0
are fitted again without them (`SMALL`), as a form without them has none.

Where those rounds leave the margin off flat (BARE_FROM), they are run again bare: each
relief read as the pose's terms alone lay the curves flat, its rise and fall past
unfold_rolled.CLEAR, and each read half way to the pose fitted (STEP). Ovate folded 75 and
twisted 0.2 is an exact fixed point of both, but a relief read in its frame turned 0.01 rad
about v or n, or lifted 5e-3 of the length, led the next round 4.7-7.7° off its fold (curl and
roll held): the hinge's steepest rise, read past pose_relief.CREASE, went from 0 to 0.49-0.76
rad, and at 0.49 the fold took 0.41 of the relief's turn (hinge_fold.fold_share). The rounds
stalled 7e-4 of the length off flat and unfold.py's fit stood (fold -31.1, curl 1.08: 0.633
wide); bare, from the same start, 2e-5 and its own pose (/work/notes/pose39).
"""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from leafstudio.core import unfold_checks as checks
from leafstudio.core.bend import Pose
from leafstudio.core.placed import PlacedPose
from leafstudio.core.plane import Frame
from leafstudio.core.pose_limits import FOLD as FOLD_LIMIT
from leafstudio.core.pose_limits import TWIST_TURNS
from leafstudio.core.pose_relief import Relief, laid_flat, slopes_off
from leafstudio.core.unfold_rolled import CLEAR
from leafstudio.model import Leaf

MIXED_FROM = 2e-4  # of the length: unfold.py's best fit leaving the margin farther off flat than
# this (rms) is fitted again here; the posed forms of csv_traits.py its fits take well are left
# 1e-13-4e-5 off, ovate folded 75 and curled 1 (2.7% narrow) 5.7e-4, cordate folded 60 and
# rolled 0.5 4.2e-4, linear rolled 1 1.3e-3, ovate folded -45 and rolled 0.4 (16.1% wide) 1.2e-3
MIXED_GAIN = 0.5  # ... and replaced when this lays it flatter than this share of that, and
# within MIXED_FROM: a form's own pose is exact here (extra_rows.py's six, 2e-8-1e-4 of the
# length), a fit past it is not the form's: rolled into tubes, whose margins meet at the seam,
# oblanceolate rolled -1 was fitted 1.3e-3 (fold 11.6 and roll 1.15 times the form's, where
# unfold.py's 5.8e-3 passed test_unfold's own-surface check), oblong rolled 1 1.3e-3, linear 4.9e-4
MIXED_KEPT = 3e-4  # ... and kept within this (MIXED_GAIN): ovate folded 60 and twisted 0.2,
# from a fold of 60 (FOLDED), swung about its own pose 2.2e-4-5.3e-4 of the length off flat
# (its curl 0.01, -0.02, 0.02, -0.03 over the diagonal) and was fitted none (pose38)
MIXED_EXPLAINED = 0.05  # a leaf unfold.py leaves unfolded is unfolded when this leaves at most
# this share of the quadric's rms (unfold.HINGE_EXPLAINED's): the six posed forms of
# extra_rows.py 0.0005-0.022 (ovate rolled 0.5 and twisted 0.5 the most)
TWISTS = (2.0, -2.0)  # the twist's starts, radians over the outline's diagonal (unfold.TWISTS)
FOLDED = (60.0,)  # the fold `mixed` starts its relief rounds from in each first frame (one of
# which stands on the margin's side: a fold of either sign is one up in it), past the plane's fits
PLAIN_CALLS = 200  # evaluations of each fit about the margin's plane, at most
KEPT = 3  # the best fits about that plane, of distinct rms, fitted about the relief
SAME = 1e-3  # ... fits whose rms is within this share of one kept are the same (a frame turned)
CALLS = 40  # evaluations of each fit about a relief, at most (they stop after 3-6)
READS = 16  # rounds of reading the relief: ovate folded 30, curled 0.5, rolled 0.3 and twisted
# 0.5 went 9.6e-4, 5.9e-4, 3.8e-4 ... 1.9e-5 of the length off flat in 12
SHEET_CLOSE = 1e-6  # ... until the sections' means move less than this share of the length,
VALUES = 9  # a fit's numbers: its frame's rotation (3), the four terms, its lift and shift
STEP = 0.5  # ... reading each next relief this share of the way to the pose the last round fitted,
# once a round leaves more than the one before: cordate folded 30, curled 0.8 and rolled 0.3
# swung between fold 29.4 and 32.6 (8.3e-4 and 1.5e-3 of the length off flat) from its own pose
# and was fitted none (30.1% narrow); so eased, 2e-7 in 16 rounds, its own pose
PATIENCE = 2  # ... or this many rounds in a row lay the margin no flatter than the best
BARE_FROM = 1e-4  # of the length: the bare rounds are run where the others' best leaves the
# margin farther off flat than this: ovate folded 65-75 and twisted 0.1-0.2, kept within
# MIXED_KEPT with a roll of -0.03 to -0.28 (65/0.2 9.9% wide, 70/0.1 3.0%), read their own pose
# at 1e-4, not at MIXED_KEPT (/work/notes/pose39/neighbours_probe_barefrom1e-4.txt)
BARE_PATIENCE = 4  # the bare rounds (module docstring) stop after this many rounds in a row
# no flatter: from ovate folded 75 and twisted 0.2 in its own frame turned 0.01 rad about v, or
# lifted 5e-3 of the length, after 2 they stopped 4.0e-4 and 4.8e-4 of the length off flat,
# after 4 1.4e-6 and 2.1e-5 (/work/notes/pose39/clean_rounds.py)
BARE_TURN = 1.0  # ... and not where the best found rolls the margin more than this (radians):
# a roll bends about its sections' means, which a bare read leaves out, and tubes rolled 1 and
# -1 (linear, oblong, oblanceolate), their best 8e-4-1.3e-3 of the length off flat and turned
# 1.7-2.9, took 1.3-3.9 s of CPU more for none kept; folded 70-75 and twisted, 0.04-0.29
GOOD = 1e-5  # of the length: a fit this flat is kept without fitting the other starts
LEADS = 4.0  # a start whose first round is this many times the best's rms is let go (the
# best found here, or unfold.py's: ovate folded 75 and curled 1, fitted 6.0e-4 of the length off
# flat there, first rounds 6.9e-4-1.1e-2 here; cordate folded 60 and rolled 0.5, 4.2e-4, 0.024)
FIRST = 0.25  # ... or, where unfold.py fitted none, this share of the quadric's rms: the first
# rounds of extra_rows.py's six forms' best starts 0.008-0.16, waved blades 0.52-0.85 (elliptic
# waved 0.2, ovate 0.05)
SMALL = (0.5, 0.01, 0.01, 0.01)  # fold (degrees), curl, roll and twist (over the diagonal)
# under these are fitted again at 0 (the rounds' noise: ovate rolled and twisted 0.5, fold 0.05)
SIMPLER = 1.5  # ... and kept at 0 when that fit leaves at most this much more
CLOSE = 1e-5  # ... plus this share of the length


def mixed(
    starts: list[PlacedPose],
    points: np.ndarray,
    midrib: np.ndarray,
    curves: list[np.ndarray],
    frames: list[np.ndarray],
    length: float,
    most: float,
    curls: float,
    lead: float = np.inf,
    noise: float = 0.0,
) -> list[tuple[float, tuple[int, ...], PlacedPose]]:
    """Fits of the fold, curl, roll and twist about a relief read off the curves (module
    docstring), best first: each the rms of the (n, 3) margin `points` off the flat blade's
    plane, its terms (unfold.TERMS': 0 fold, 1 curl, 2 roll, 3 twist) and the pose.

    `starts`: unfold.py's fits (their frames' origins on the normal through `midrib[0]`, the
    (m, 3) midrib's base); `curves` the boundary and veins whole; `frames` unfold's first
    (3, 3) frames; `length` the outline's diagonal, `most` the roll's search and `curls` the
    curl's (pose_limits.fit_bounds', as unfold.py's fits: a blade wider than long curls past
    CURL_SEARCH over its diagonal), each way, in its units; a start whose first round about a
    relief leaves more than `lead` is let go, taken beyond the margin's digitising `noise`
    (unfold_checks.above_noise, as unfold.py's fits; the rms returned are as fitted: `remixed`)."""
    origin = midrib[0]
    weight = 1.0 / np.sqrt(len(points))

    def beyond(rms: float) -> float:
        return checks.above_noise(rms, noise, VALUES, len(points))

    # rotation, fold, curl, roll, twist (these three times the length), lift and shift (shares)
    hi = np.array([np.pi] * 3 + [FOLD_LIMIT, curls, most, TWIST_TURNS * np.pi, 1.0, 0.5])
    chord = float(np.linalg.norm(midrib[-1] - origin))

    def placed(y: np.ndarray, axes: np.ndarray, relief: Relief | None) -> tuple:
        """The pose of (9,) `y` about `relief` in `axes` turned, the origin lifted along the
        normal and shifted along the midrib; the margin's points in its frame."""
        turned = Rotation.from_rotvec(y[:3]).apply(axes)
        offset = y[8] * length * turned[0] + y[7] * length * turned[2]
        blade = (points - origin - offset) @ turned.T
        pose = Pose(float(y[3]), *(float(t) / length for t in y[4:7]), relief)
        return PlacedPose(pose, Frame(origin + offset, *turned)), blade

    def read(bend: PlacedPose, bare: bool = False) -> Relief | None:
        """The relief of the curves as `bend` lays them flat (a form's, relief_of); `bare`: as
        its terms lay them without its relief, its rise and fall past CLEAR (module docstring)."""
        if not bare:
            return laid_flat(bend.pose, bend.frame, curves)[1]
        flat, relief = laid_flat(replace(bend.pose, relief=None), bend.frame, curves)
        if relief is None:
            return None
        return relief.sloped(*slopes_off(relief, np.vstack(flat), CLEAR))

    def fitted(
        axes: np.ndarray, y: np.ndarray, relief: Relief | None, free: list[int], calls: int
    ) -> tuple[float, np.ndarray]:
        """A fit of `y`'s entries `free` (the rest kept) about `relief`, of at most `calls`
        evaluations: rms and (9,) y."""

        def residual(z: np.ndarray) -> np.ndarray:
            full = y.copy()
            full[free] = z
            bend, blade = placed(full, axes, relief)
            return weight * bend.pose.flatten(blade)[:, 2] / length

        start = np.clip(y[free], -hi[free], hi[free])
        fit = least_squares(residual, start, bounds=(-hi[free], hi[free]), max_nfev=calls)
        found = y.copy()
        found[free] = fit.x
        return float(np.sqrt(2 * fit.cost)) * length, found

    def settled(
        axes: np.ndarray,
        y: np.ndarray,
        relief: Relief | None,
        free: list[int],
        lead: float,
        bare: bool = False,
    ) -> tuple:
        """Rounds of fits of `free` from (9,) `y`, the first about `relief`, each next about
        the relief read off the curves as the last laid them flat: the best's rms, y and
        relief (rms inf when the first round leaves more than `lead`). Once a round leaves
        more than the one before, each next relief is read part way (STEP) from the pose the
        last was read at to the pose fitted about it; `bare`: each read so, bare (the module
        docstring)."""
        best, worse, last, step, at = (np.inf, y, relief), 0, np.inf, (STEP if bare else 1.0), y
        patience = BARE_PATIENCE if bare else PATIENCE
        for round_ in range(READS):
            if relief is None:
                break
            rms, y = fitted(axes, y, relief, free, CALLS)
            if round_ == 0 and beyond(rms) > lead:  # another start's basin leads
                break
            if rms < best[0]:
                best, worse = (rms, y, relief), 0
            else:
                worse += 1
                if worse > patience:
                    break
            step, last = (STEP if rms > last else step), rms
            at = at + step * (y - at)  # the pose the next relief is read at
            was, relief = relief, read(placed(at, axes, relief)[0], bare)
            if relief is None or (
                np.abs(np.subtract(relief.mean, was.mean)).max() <= SHEET_CLOSE * length
            ):
                break
        return best

    grid = []
    for start in starts:
        axes = np.array([start.frame.u, start.frame.v, start.frame.normal])
        p = start.pose
        lift = float((start.frame.origin - origin) @ axes[2]) / length
        terms = [p.fold, p.curl * length, p.roll * length, p.twist * length]
        grid.append((axes, np.array([0.0, 0.0, 0.0, *terms, lift, 0.0])))
    for axes, roll, twist in itertools.product(frames, (most / 2, -most / 2), TWISTS):
        turn = -twist * chord / (2 * length)  # the boundary's plane sees the blade's middle
        turned = Rotation.from_rotvec(turn * axes[0]).apply(axes)
        grid.append((turned, np.array([0.0, 0.0, 0.0, 0.0, 0.0, roll, twist, 0.0, 0.0])))
    every = list(range(VALUES))
    plain = sorted(
        (fitted(axes, y, None, every[:8], PLAIN_CALLS) + (axes,) for axes, y in grid),
        key=lambda f: f[0],
    )
    kept: list[tuple] = []
    for fit in plain:  # distinct basins: the same rms is the same fit (or its frame turned)
        if len(kept) < KEPT and all(abs(fit[0] - k[0]) > SAME * k[0] for k in kept):
            kept.append(fit)
    # and a fold of either sign from each first frame, read about a relief at once: the fits
    # about the margin's plane took every start of ovate folded 60 and twisted 0.2 to fold 26-32
    # and a curl of -1 (the plane's shear), whose relief rounds stalled at 4.2e-3 of the length
    # off flat; from fold 60 the form's own pose (pose38)
    kept += [
        (np.inf, np.array([0.0] * 3 + [fold] + [0.0] * 5), axes)
        for axes in frames
        for fold in FOLDED
    ]
    found: list[tuple] = []  # (rms, y, axes, relief, bare)
    for bare in (False, True):  # bare where the others leave it off flat
        if bare and (
            not found
            or beyond(found[0][0]) <= BARE_FROM * length  # as GOOD: noise is no fold to read
            or np.pi * abs(found[0][1][5]) / most > BARE_TURN  # its roll's turn at the margin
        ):
            break
        for _, y, axes in kept:
            first = min(lead, LEADS * beyond(found[0][0])) if found else lead
            relief = read(placed(y, axes, None)[0], bare)
            rms, y, relief = settled(axes, y, relief, every, first, bare)
            if relief is not None and np.isfinite(rms):
                found.append((rms, y, axes, relief, bare))
                found.sort(key=lambda f: f[0])
                if beyond(found[0][0]) <= GOOD * length:
                    break
    if not found:
        return []
    rms, y, axes, relief, bare = found[0]
    fits = [(rms, (0, 1, 2, 3), placed(y, axes, relief)[0])]
    small = [i for i in range(4) if abs(y[3 + i]) < SMALL[i]]
    if small:  # near 0: fitted again at 0 about the relief found
        again = np.where(np.isin(np.arange(VALUES), [3 + i for i in small]), 0.0, y)
        free = [i for i in every if i - 3 not in small]
        rms, y, relief = settled(axes, again, relief, free, np.inf, bare)
        if relief is not None and np.isfinite(rms):
            terms = tuple(i for i in range(4) if i not in small)
            fits.append((rms, terms, placed(y, axes, relief)[0]))
    return fits


def remixed(
    best: tuple | None,
    starts: list[PlacedPose],
    leaf: Leaf,
    points: np.ndarray,
    midrib: np.ndarray,
    frames: list[np.ndarray],
    length: float,
    most: float,
    curls: float,
    before: float,
    noise: float = 0.0,
) -> tuple | None:
    """unfold.py's `best` fit ((rms, terms, bend, ...) or None), or `mixed`'s best where that
    leaves the margin off flat (MIXED_FROM) and `mixed` lays it within MIXED_KEPT and flatter
    (MIXED_GAIN), or, where there is none, within MIXED_KEPT and flat enough against `before`, the
    quadric's rms (MIXED_EXPLAINED); its fewer terms where they do about as well (SIMPLER,
    CLOSE). `best` and `before` are taken beyond the margin's digitising `noise`, and so are
    `mixed`'s fits where there is no `best`; else they replace it only when flatter than it as
    fitted (a relief read off noisy curves takes up some of their noise: cordate folded 45 and
    given 5e-4 of the length of it was fitted fold 46.3, roll -0.14, 1.4% narrow, not fold
    44.8). With 5e-4 of noise, obovate curled 0.5 and rolled 0.4, reniform curled -1 and rolled
    -0.3, cordate folded 30, curled 0.8 and rolled 0.3 were fitted none (3 of 3 seeds). The
    arguments as `mixed` takes
    them; `leaf` the unit leaf (whether a fit lies flat: unfold_checks.lies_flat)."""
    if best is not None and best[0] <= MIXED_FROM * length:
        return best
    lead = FIRST * before if best is None else LEADS * best[0]
    curves = [leaf.boundary, *leaf.veins]
    fits = mixed(starts, points, midrib, curves, frames, length, most, curls, lead, noise)
    fits = [f for f in fits if checks.lies_flat(f[2], leaf)]
    if not fits:
        return best
    if best is None:  # nothing to keep: taken beyond the noise as unfold.py's fits
        fits = [(checks.above_noise(f[0], noise, VALUES, len(points)), *f[1:]) for f in fits]
    rms, terms, bend = checks.simplest(fits, SIMPLER, CLOSE * length)
    if rms > MIXED_KEPT * length:  # not a form's own pose (MIXED_GAIN: tubes)
        return best
    if rms <= (MIXED_GAIN * best[0] if best is not None else MIXED_EXPLAINED * before):
        return rms, terms, bend
    return best
