"""Curves in 3D unfolded (issue 21, build item 2): a leaf given as boundary and veins in 3D
without a bend (a posed form saved without its pose, a drawn leaf lifted in the side view) gets
the bend that lays them flat, fitted to them.

A leaf's margin and midrib lie on its flat blade (the relief rides on the side veins); a fold,
curl or roll lifts them off any plane, and the boundary's PCA plane then sees a folded or curled
blade side-on (a fold of 75°: the mesh 5% of the length off the form's own surface on average).
`fit_pose` finds the blade's frame (the base at the midrib's base end, u along it) and the
`Pose` (fold, curl, roll, twist) whose `flatten` brings the margin and the midrib nearest one
plane, by least squares over the frame's rotation and the pose's terms. The leaf is unfolded only
when its margin is well off a plane, or off the best quadratic height field over it (a fold
down and a roll up), and the pose lays it much flatter than that height field would, or, when
that plane sees it side-on (a whole vein outside the outline there: the pipeline would refuse it
or mesh a side view), whenever a pose lays it flat; when its outline crosses itself on that
plane (the app and the commands refuse it), when the hinge explains it a little less strictly
(HINGE_CROSSED), a real crossing staying refused. A flat, cupped or gently bent leaf runs as
before (its margin's heights go to the paper's base b(x)); `core/unfolded.py` asks once per
curves.

Those fits fold about the margin's plane, which shears each half; once a leaf is to be
unfolded, each fit is fitted again about the midrib's hinge as the pose lays it flat, with the
margin's rise and fall off it (core/unfold_hinge.py, which says what that changed), and kept
where it lays the margin clearly flatter (HINGE_GAIN). Whether to unfold is asked of those only
where the fits about the margin's plane fall short, and far more strictly (HINGE_EXPLAINED).
A form rolls each cross-section about its own mean height, 2-8% of the length over the margin:
a roll alone is fitted again about the sections' means read off the curves as the round before
laid them flat (`sheeted`, pose_relief.sheet_relief), and asked whether to unfold where the
others fall short (SHEET_EXPLAINED: a tube a quadric nearly takes).

A fold and a roll that lift the margins the same way are fitted again about a form's relief
(core/unfold_rolled.py: about the hinge alone, oblong folded 45 and rolled 0.5, as a CSV, read
back 36% too wide), a mix the fits leave off flat with all four terms (core/unfold_mixed.py). A
curl is searched as far as it turns the midrib (pose_limits.fit_bounds), a curl alone from the
midrib's own turn too (core/unfold_curl.py): reniform curled 1 and -1 read back 1.126 and 0.733.

A margin digitised with noise is no flatter under any pose: each fit's rms, and the quadric's, is
taken beyond the noise read off the margin (unfold_checks.above_noise); and a bowl, a blade
curled and rolled one way, whose rim lies nearly on a plane, is asked by its midrib sunk under it
(unfold_checks.FORESHORTENED).

The twist (bend.Pose's: each cross-section turned about the midrib by twist · x) is fitted only
where no pose without it lays the margin flat (TWIST_FROM), over the same subsets with the twist
added (TWISTED), and kept where it lays it clearly flatter (TWIST_GAIN): without it an ovate
folded 60 and twisted 1, saved as a CSV, was fitted a curl of 1.2 in a turned frame and came back
1.28 long; cordate so posed was fitted a roll and refused (a vein outside the outline), ovate
twisted 1 refused (its outline crossing itself). A leaf laid flat without it is fitted as before.
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
from leafstudio.core.pose_limits import FIT_POINTS, fit_bounds  # the fit's points; its bounds
from leafstudio.core.pose_limits import FOLD as FOLD_LIMIT  # the fold's search range, each way
from leafstudio.core.pose_limits import TWIST_TURNS as TWIST_HALVES  # the loader's twist, at most
from leafstudio.core.pose_relief import Relief, relief_of, sheet_relief
from leafstudio.core.prepare.vein_order import midrib_turned
from leafstudio.core.unfold_curl import bowed_starts
from leafstudio.core.unfold_frames import first_frames, upright
from leafstudio.core.unfold_hinge import SHARE_CLOSE, fallen_slopes, hinge_relief, turn_share
from leafstudio.core.unfold_mixed import remixed
from leafstudio.core.unfold_rolled import refolded
from leafstudio.model import Leaf

EXPLAINED = 0.25  # ... and is unfolded when the fitted pose leaves at most this share of what
# the best quadratic height field over that plane leaves (the paper's base takes such a margin)
FOLDS = (0.0, 60.0, -60.0)  # the fold's first guesses
# fold, curl, roll (0, 1, 2): all three first (a leaf no pose explains is left after one fit),
# then the fewer that may do as well
TERMS = ((0, 1, 2), (0,), (1,), (2,), (0, 1))
TWISTED = ((0, 1, 3), (3,), (0, 3), (1, 3))  # ... then with the twist (3), the same way. Not a
# roll and a twist together: with (2, 3) and a twist's start at 0, a leaf no pose explains (four
# waved blades, reniform curled -1) took 1.6-2.1 times the Pose.flatten calls it took without a
# twist, without them 1.4-1.9 (/work/notes/unfold33/probe_cost.py)
TWIST_FROM = 1e-3  # the twist is fitted when no pose without it lays the margin within this
# share of the length of flat (rms): the 17 untwisted posed forms of csv_traits.py were left
# 3e-13-6e-4 (ovate folded 75 and curled 1) but for linear rolled 1 (1.3e-3) and cordate folded
# 60 and rolled 0.5 (2.0e-3; 4.6e-4 since unfold_rolled.py), which the twist left as they
# were; twisted forms 1.7e-3
# (lanceolate curled 0.6, twisted 0.5), 0.023-0.025 (ovate and cordate folded 60, twisted 1), or
# none (ovate, linear twisted 1, elliptic folded 30 and twisted 0.5)
TWIST_GAIN = 0.5  # ... and kept when it lays it flatter than this share of their best: twisted
# forms 1e-3-0.04 of it; the two untwisted past TWIST_FROM were given no twisted fit
TWISTS = (2.0, -2.0)  # the twist's first guesses, radians over the outline's diagonal: from 0
# and 1 the fit of ovate folded 60 and twisted 1 (pi over its length) went to a roll of 2.4; the
# untwisted pass has tried 0
TWIST_LIMIT = TWIST_HALVES * np.pi  # the twist's search, radians over that diagonal each way:
# the apex, no farther than the diagonal from the base, turns at most what the loader takes
SIMPLER = 1.5  # fewer terms are taken when they leave at most this much more than all three
CLOSE = 2e-4  # ... plus this share of the length
HINGE_EXPLAINED = 0.05  # a leaf the fits about the margin's plane leave unexplained is unfolded
# when the fit about the midrib's hinge leaves at most this share of the quadric's: 0.001-0.007
# on folded lobed and domed forms (fold ±30-60), 0.19-0.52 on waved blades (ovate, elliptic,
# linear, lanceolate, cordate; wave 0.1-0.2)
HINGE_CROSSED = 0.1  # ... at most this share for a leaf whose outline crosses itself on its
# plane as given (refused as it is): deltoid folded 30 and rolled 0.4, 0.070; a lanceolate folded
# -60 and rolled 0.3 with two neighbouring boundary points swapped, a real crossing, took any pose
# that hid it (fold -19.5, 1.08 times its width) when any pose that lay flat was let through
HINGE_CALLS = 30  # ... each of those fits stops after this many evaluations: a fold the hinge
# explains took 4-15 from its start (sagittate folded 60, ovate folded -60, sagittate folded 45
# and curled 0.3), elliptic waved 0.2 wandered for 386 (12.5 s of CPU); and so does every fit
# about the hinge (_fit's `eased`): spatulate folded -75 took 30 s of CPU uncapped, 2.8 capped,
# to the same fold (-74.96)
SHEET_EXPLAINED = 0.5  # ... or when a roll alone about each section's mean height (`sheeted`)
# leaves at most this share of the quadric's: 2e-5-0.022 on the 14 shapes rolled 0.3 and 0.5,
# 0.45 orbicular rolled 0.8 (a tube the quadric nearly takes; its sheet read again is up to
# 1.4e-3 of the length off: relief_of samples another box), waved and toothed blades 0.97-1.04
SHEET_ROUNDS = 8  # ... each round reading the sheet off the curves the last laid flat: oblong
# rolled 0.5 left 8.5e-4, 2.3e-4, 1.1e-4, 5.9e-5 of the length in four
SHEET_CLOSE = 1e-4  # ... until the sheet moves less than this share of the length,
SHEET_STALL = 0.99  # ... or the rms falls by less than this (a waved blade's stays), the best
# round kept: at 0.9 linear rolled 1, as a CSV, stopped at its third round (rms 1.32e-3 of the
# length after 1.69e-3 and 1.44e-3; roll 82.3, 85.9, 87.0 of the form's 87.96), 1.1% wide; its
# fourth 1.30e-3 and 87.4 (0.7%), its fifth 1.36e-3. Let run, the rounds drift away (rms rising,
# roll 94.8 by the 16th, then 37). The 48 other rows of /work/notes/pose37/repro.py read back
# the same to 0.1% (orbicular rolled 0.8's roll 5.028 -> 5.029), their CPU as before
HINGE_GAIN = 0.9  # a fit about the hinge is kept when its rms is at most this share of the
# fit's about the margin's plane: 0.001-0.30 on the folded test forms, 0.80 on ovate rolled 0.5
# (its own surface 3.2e-4 -> 2.8e-4 off on average); 0.999 on a rolled grass blade, whose fold of
# -11° went to -13° (3.3e-4 -> 3.6e-4), and 0.985-0.994 for a curl alone: no sign of a fold
EASED_FROM = 60.0  # degrees: a fit folded harder than this about the margin's plane is tried
# about the hinge from its fold alone too (_fit; a form's dome turns rigidly up to 60°): the
# retry on every fit that gained nothing took a rolled grass blade's fit 1.3 -> 3.6 s of CPU
NO_BEND = 1e-6  # degrees of fold, or radians over the unit leaf of curl, roll and twist: a
# pose whose terms are all under this bends nothing (_no_bend)
FALL_FITS = 12  # fits about the hinge, each with the rise and fall the last left (_fit): the
# fold and curl of lanceolate folded -75 went 75.30, 76.29, 76.07 ... 75.19 in 12 (0.07 s each)
HINGE_SIZES = (1e-100, 1e100)  # a leaf's extent outside these: its pose has no relief (scipy's
# splines of a relief in its units cube x: -inf at 1e110, "dydx must contain only finite
# values" at 1e300; the pose fitted about the margin's plane, as before, runs to 1e150)


def fit_pose(leaf: Leaf) -> PlacedPose | None:
    """The bend that lays `leaf`'s margin and midrib flat, or None when the leaf is flat enough
    as it is or no pose explains its bend (module docstring).

    Parameters
    ----------
    leaf : Leaf
        Boundary and veins in 3D (the midrib first), without a bend.

    Returns
    -------
    PlacedPose or None
        The fitted fold, curl, roll and twist in the blade's frame (base at the midrib's base end:
        vein_order.midrib_turned).
    """
    if leaf.bend is not None or not leaf.veins or len(leaf.veins[0]) < 3:
        return None
    lo, hi = leaf.boundary.min(axis=0), leaf.boundary.max(axis=0)
    centre, half = lo / 2 + hi / 2, float(np.max(hi / 2 - lo / 2))
    if not (np.isfinite(half) and half > 0):
        return None

    def unit(points: np.ndarray) -> np.ndarray:  # about unit size: no overflow at 1e300
        return (points / 2 - centre / 2) / half

    hinged = HINGE_SIZES[0] < 2 * half < HINGE_SIZES[1]
    boundary = unit(leaf.boundary)
    if not checks.bent(boundary, unit(leaf.veins[0])):  # flat, cupped or gently bent: the unit
        return None  # leaf is not made (0.17 ms of a flat ovate's 0.35, best of 40), nor its
        # midrib's way asked
    bend = _fit(Leaf(boundary, [unit(v) for v in leaf.veins]), hinged)
    if bend is None or _no_bend(bend.pose):
        return None
    pose, frame = bend.pose, bend.frame
    relief = None if pose.relief is None else pose.relief.scaled(2 * half)
    return upright(
        PlacedPose(
            Pose(pose.fold, *(t / (2 * half) for t in (pose.curl, pose.roll, pose.twist)), relief),
            Frame(
                origin=centre + 2 * half * frame.origin, u=frame.u, v=frame.v, normal=frame.normal
            ),
        ),
        leaf,
    )


def _no_bend(pose: Pose) -> bool:
    """Whether every term of a pose fitted at unit size is nought (NO_BEND): a waved elliptic
    blade as a point CSV (wave 0.2) was fitted fold 1e-27, curl 4e-44, roll -6e-10 about a
    relief of zeros, and as so bent its surface came out 22% smaller than the form's own; unbent,
    as a waved blade of wave 0.1 is left, the base b(x) follows its margin's heights (0.0%)."""
    return all(abs(t) < NO_BEND for t in (pose.fold, pose.curl, pose.roll, pose.twist))


def _fit(leaf: Leaf, hinged: bool = True) -> PlacedPose | None:
    """fit_pose on the leaf at about unit size, off its plane (fit_pose asks); the poses fitted
    again about the midrib's hinge when `hinged`."""
    boundary, midrib = leaf.boundary, leaf.veins[0]
    length = float(np.linalg.norm(np.ptp(boundary, axis=0)))
    if midrib_turned(list(leaf.veins)):  # written apex first: the frame's origin is the base
        midrib = midrib[::-1]
    # each fit's rms is taken beyond the margin's noise (above_noise), and the quadric's: the
    # pose must do much better than a height field
    noise = checks.margin_noise(boundary, leaf.veins[0])
    before = checks.above_noise(checks.off_quadric(boundary), noise, 6, len(boundary))
    if checks.side_on(leaf, length):  # ... unless the leaf as given is refused: any pose
        # that lays it flat does better (folded down 70°, the halves nearly closed: fitted
        # 0.0107 against the quadric's 0.0259, and the pipeline refused its midrib as outside
        # the outline)
        before = np.inf
    # an outline crossing itself on its plane as given is refused too, but may be a real
    # crossing: the hinge may explain a little less (HINGE_CROSSED; deltoid folded 30 and
    # rolled 0.4: 0.41 of the quadric's rms about the margin's plane, 0.070 about the hinge)
    hinge_share = HINGE_CROSSED if checks.crosses(leaf) else HINGE_EXPLAINED
    # the margin's farthest from the midrib's chord: at most the flat blade's half-width, so a
    # roll up to half a turn each side is within pi / reach, a quarter turn the roll's first
    # guess (pose_limits.fit_bounds: the loader takes what this searched)
    curls, _, _, reach = fit_bounds(boundary, midrib)
    most, curls = np.pi * length / reach, curls * length  # in the fit's units
    boundary = boundary[:: max(1, len(boundary) // FIT_POINTS)]  # enough to fit six numbers
    midrib = np.vstack([midrib[:: max(1, len(midrib) // FIT_POINTS)], midrib[-1:]])
    origin = midrib[0]
    points = boundary - origin  # the margin lies flat; the midrib, with its relief, need not
    weight = 1.0 / np.sqrt(len(points))
    first_axes = first_frames(boundary, midrib)  # every fit's first frames

    def beyond(rms: float, free: int) -> float:
        return checks.above_noise(rms, noise, free, len(points))

    def placed(
        x: np.ndarray,
        axes: np.ndarray,
        hinged: bool,
        slopes: tuple[float, float] = (0.0, 0.0),
        sheet: tuple | None = None,
    ) -> tuple[PlacedPose, np.ndarray]:
        """The pose of a fit's (8,) `x` in its frame (the (3, 3) `axes` turned), with the
        hinge's relief (`hinge_relief`, its rise and fall `slopes`, its roll's `sheet`) when
        `hinged`, and the margin's points in that frame."""
        turned = Rotation.from_rotvec(x[:3]).apply(axes)  # rows u, v, normal
        lift = [0.0, 0.0, x[7] * length]
        blade = points @ turned.T - lift
        pose = Pose(float(x[3]), *(float(t) / length for t in x[4:7]))  # fold; curl, roll, twist
        if hinged:
            hinge = hinge_relief(pose, (midrib - origin) @ turned.T - lift, blade, slopes, sheet)
            pose = replace(pose, relief=hinge)
        u, v, n = turned
        frame = Frame(origin=origin + x[7] * length * n, u=u, v=v, normal=n)
        return PlacedPose(pose, frame), blade

    def full(y: np.ndarray, terms: tuple[int, ...]) -> np.ndarray:
        """(8,) the rotation, fold, curl, roll, twist and the base's height from a fit's
        (4 + k,)."""
        x = np.zeros(8)
        x[:3], x[7] = y[:3], y[3]
        x[[3 + t for t in terms]] = y[4:]
        return x

    def fits_of(
        terms: tuple[int, ...],
        starts: list,
        hinged: bool = False,
        most_calls: int | None = None,
        slopes: tuple[float, float] = (0.0, 0.0),
        about: Relief | None = None,
    ) -> list[tuple]:
        """Fits of `terms` from `starts` ((axes, (4 + k,) y) each), best first: each its
        margin's rms off the flat blade's plane, (8,) x, axes and (4 + k,) y; each fit stops
        after `most_calls` evaluations when given; about a hinge of rise and fall `slopes` when
        `hinged`, or bent about the relief `about` when given (a roll alone: `sheeted`)."""
        hi = [np.pi] * 3 + [1.0] + [(FOLD_LIMIT, curls, most, TWIST_LIMIT)[t] for t in terms]
        found = []
        for axes, y0 in starts:

            def residual(y: np.ndarray, axes: np.ndarray = axes) -> np.ndarray:
                bend, blade = placed(full(y, terms), axes, hinged and about is None, slopes)
                pose = bend.pose if about is None else replace(bend.pose, relief=about)
                return weight * pose.flatten(blade)[:, 2] / length

            fit = least_squares(residual, y0, bounds=([-h for h in hi], hi), max_nfev=most_calls)
            found.append((float(np.sqrt(2 * fit.cost)) * length, full(fit.x, terms), axes, fit.x))
        found.sort(key=lambda f: f[0])  # the best first, then their rms beyond the noise
        return [(beyond(f[0], len(f[3])), *f[1:]) for f in found]

    def flat_fit(tried: list, terms: tuple[int, ...]) -> tuple | None:
        """(rms, terms, bend, axes, y) of the first of the `tried` (`fits_of`) that lies flat,
        or None."""
        for rms, x, axes, y in tried:
            bend = placed(x, axes, False)[0]
            if checks.lies_flat(bend, leaf):
                return rms, terms, bend, axes, y
        return None

    def hinge_explains(start: tuple, terms: tuple[int, ...]) -> bool:
        """Whether a fit about the midrib's hinge leaves at most `hinge_share` of `before`:
        the fold alone from each frame's folded starts (a fit of one round of `hinge_relief` a
        step; not for twisted `terms`), else `terms` from the fit about the margin's plane's
        best `start` ((axes, y)): on oblanceolate folded -60 that best, fold -31 and roll -24
        making up for the shear, led the hinge's fit to 0.78 of `before`; the fold alone from
        -60, to 2e-4."""
        frames = itertools.product(first_axes, FOLDS[1:])
        starts = [(axes, np.array([0.0] * 4 + [fold])) for axes, fold in frames]
        if (
            3 not in terms
            and fits_of((0,), starts, True, HINGE_CALLS)[0][0] <= hinge_share * before
        ):
            return True
        if fits_of(terms, [start], True, HINGE_CALLS)[0][0] <= hinge_share * before:
            return True
        if 3 in terms:
            return False
        # else a roll alone about each section's own mean height, as a form rolls: about the
        # margin's plane, oblong rolled 0.5 was left 0.82 of `before` (8.8e-3 of the length off
        # its own surface at p95 as a height field), about its sections 0.011 (3.5e-5)
        rolled.append(sheeted(found_of((2,))[0][2:]))
        return rolled[0][0] <= SHEET_EXPLAINED * before

    def eased(start: tuple, terms: tuple[int, ...]) -> tuple:
        """A fit of `terms` about the midrib's hinge from `start` ((axes, y)), its halves turned
        rigidly, then again in up to FALL_FITS rounds with the relief's rise and fall as the
        margin lies flat (`fallen_slopes`), while the share of the fold's turn they give moves: its
        rms, (8,) x, axes and the rise and fall."""
        again, x, axes, y = fits_of(terms, [start], True, HINGE_CALLS)[0]
        slopes = (0.0, 0.0)
        for _ in range(FALL_FITS):
            bend, blade = placed(x, axes, True, slopes)
            if bend.pose.relief is None:  # the midrib doubles back: no hinge
                break
            fallen = fallen_slopes(bend.pose, blade)
            given = bend.pose.relief.sloped(*fallen)
            if (
                abs(turn_share(bend.pose, given) - turn_share(bend.pose, bend.pose.relief))
                <= SHARE_CLOSE
            ):
                break
            slopes = fallen
            again, x, axes, y = fits_of(terms, [(axes, y)], True, HINGE_CALLS, slopes)[0]
        return again, x, axes, slopes

    rolled, plain = [], {}  # `sheeted`'s fit once asked (hinge_explains); found_of's fits

    def sheeted(start: tuple) -> tuple:
        """The roll alone from `start` ((axes, y)) about each section's own mean height (a
        form's, relief_of's), read off the curves the round before laid flat: the best round's
        rms, x, axes, y, sheet."""
        (axes, y), about, sheet, rms = start, None, None, np.inf
        best = None  # the round that leaves the least (SHEET_STALL)
        x = full(y, (2,))
        for _ in range(SHEET_ROUNDS):
            bend = placed(x, axes, False)[0]
            pose = replace(bend.pose, relief=about)
            curves = [np.column_stack(bend.frame.to_plane(c)) for c in (leaf.boundary, *leaf.veins)]
            flat = [pose.flat_curve(c, ring=i == 0) for i, c in enumerate(curves)]
            relief = relief_of(flat[0], flat[1:])
            if relief is None:
                break
            was, sheet = sheet, (relief.knots, relief.mean)
            about = sheet_relief(*sheet)  # a roll alone asks nothing of the hinge
            starts = [(axes, y)]
            if was is None:  # the first round from every fit about the plane too, once each
                starts += [f[2:] for f in found_of((2,)) if f[3] is not y]
            last, (rms, x, axes, y) = rms, fits_of((2,), starts, about=about)[0]
            if best is None or rms < best[0]:
                best = (rms, x, axes, y, sheet)
            if was is not None and (
                np.abs(np.subtract(sheet[1], was[1])).max() <= SHEET_CLOSE
                or rms > SHEET_STALL * last
            ):
                break
        return (rms, x, axes, y, sheet) if best is None else best

    def found_of(terms: tuple[int, ...]) -> list:
        """`fits_of` `terms` about the margin's plane from every first frame and guess, once."""
        if terms not in plain:
            folds = FOLDS if 0 in terms else (0.0,)
            rolls = (0.0, most / 2, -most / 2) if 2 in terms else (0.0,)
            twists = TWISTS if 3 in terms else (0.0,)
            starts = []
            frames = itertools.product(first_axes, folds, rolls, twists)
            for axes, fold, roll, twist in frames:
                guess = [(fold, 0.0, roll, twist)[t] for t in terms]
                starts.append((axes, np.array([0.0] * 4 + guess)))
            if terms == (1,):  # and the midrib's own turn, where it turns (unfold_curl)
                starts += bowed_starts(midrib, first_axes, terms, length, curls)
            plain[terms] = fits_of(terms, starts)
        return plain[terms]

    def settle(sets: tuple[tuple[int, ...], ...]) -> tuple | None:
        """The fit over the subsets `sets` of the pose's terms (TERMS or TWISTED), the first
        asking whether the leaf is unfolded at all: (rms, terms, bend, axes, y), or None."""
        tried = []  # (terms, its fits_of, best first) per subset of the pose's terms
        for terms in sets:
            found = found_of(terms)
            # a domed blade folded about its midrib is not a fold about the margin's plane: that
            # fit's shear left 0.31 of the quadric's rms on sagittate folded 60, 0.66 on ovate
            # folded -60; the fold about the hinge leaves 0.0066 and 0.0046 (a waved blade's 0.19
            # or more). Where the plane's fit falls short, the hinge decides (HINGE_EXPLAINED)
            explained = found[0][0] <= EXPLAINED * before
            if terms == sets[0] and not (
                explained or (hinged and hinge_explains(found[0][2:], terms))
            ):
                return None
            tried.append((terms, found))
        # each subset's best start, if it lies flat; when none does, the best start of each that
        # does: which start was best turns on round-off (an ovate folded -75, written to a CSV of 9
        # digits, 5e-10 off, was refused; orbicular and reniform folded -75 were refused always).
        # Not the best that lies flat always: rolled tubes then took three terms where a roll alone
        # lies flat nearer their own surface (linear roll 1: 7.6e-4 off it on average, not 1.8e-4)
        for tries in (1, None):
            fits = [f for terms, found in tried if (f := flat_fit(found[:tries], terms))]
            if fits:
                break
        if not fits:
            return None
        plane = (
            checks.simplest(fits, SIMPLER, CLOSE * length)[0] <= EXPLAINED * before
        )  # the margin's plane explains it
        if not hinged:
            return checks.simplest(fits, SIMPLER, CLOSE * length) if plane else None
        # each pose found, fitted again folding each half rigidly about the midrib
        # (`hinge_relief`), is kept when it lays the margin flatter (a fold's shear, which a roll
        # made up for, is gone); whether the leaf is unfolded at all is the fits' above, or,
        # where they fall short, the hinge's at HINGE_EXPLAINED: the hinge, which follows the
        # midrib's own heights, also lays a waved flat blade's margin flatter than the quadric
        # (linear, wave 0.1), never so flat
        for i, (rms, terms, _, axes, y) in enumerate(fits):
            if terms == (2,):  # a roll alone bends about the sheet, z = 0 with a relief or without
                continue
            again, x, axes, slopes = eased((axes, y), terms)
            hard = 0 in terms and abs(y[4]) > EASED_FROM  # y[4]: the fold, terms in order
            if again > HINGE_GAIN * rms and hard and len(terms) > 1:  # from its fold alone:
                # a roll made up for the shear, and obovate folded -75 fitted about the hinge from
                # its fold 66.8 and roll went to 62.3 (0.0204 off); from its fold alone 75.0, 0.6251
                # wide (its flat 0.6250)
                alone = np.where(np.arange(len(y)) > 4, 0.0, y)
                again, x, axes, slopes = min(
                    (again, x, axes, slopes), eased((axes, alone), terms), key=lambda f: f[0]
                )
                if again > HINGE_GAIN * rms:  # from the frame the margin stands on, untilted
                    # (first_frames: its normal the margin's side of the midrib, a fold up in
                    # it); from the plane's fit's frame, elliptic folded -75 (fitted 72.4 and
                    # rolled -15, its frame tilted 37°) went to -46.5 and rolled 2.3 about the
                    # hinge (0.0044 off), from its fold alone there to -24.3 (1.9 times the
                    # plane's fit's rms)
                    start = np.zeros(len(y))
                    start[4] = abs(y[4])
                    again, x, axes, slopes = min(
                        (again, x, axes, slopes),
                        eased((first_axes[-1], start), terms),
                        key=lambda f: f[0],
                    )
            bend = placed(x, axes, True, slopes)[0]
            if again <= HINGE_GAIN * rms and checks.lies_flat(bend, leaf):
                fits[i] = (again, terms, bend, axes, y)
        if (2,) not in sets:  # twisted: no roll alone
            best = checks.simplest(fits, SIMPLER, CLOSE * length)
            return best if plane or best[0] <= hinge_share * before else None
        # a roll alone about each section's own mean height (`sheeted`), kept when it lays the
        # margin flatter (or when no roll about the plane lay flat: cordate rolled 1 took fold
        # 11): 8 of the 14 shapes rolled 0.5 were 1.7e-3-8.8e-3 of the length off their own
        # surface at p95, now at most 4.2e-4 (ovate fitted fold 9.6, curl 0.04 and roll 3.66:
        # 9.0e-4, now 5.2e-5)
        at = next((i for i, f in enumerate(fits) if f[1] == (2,)), len(fits))
        rms, start = (
            (fits[at][0], fits[at][3:]) if at < len(fits) else (np.inf, found_of((2,))[0][2:])
        )
        again, x, axes, y, sheet = rolled[0] if rolled else sheeted(start)
        bend = placed(x, axes, True, sheet=sheet)[0]
        if sheet is not None and again <= HINGE_GAIN * rms and checks.lies_flat(bend, leaf):
            fits[at : at + 1] = [(again, (2,), bend, axes, y)]
            plane = plane or again <= SHEET_EXPLAINED * before
        best = checks.simplest(fits, SIMPLER, CLOSE * length)
        if not plane and best[0] > hinge_share * before:  # nor the hinge
            return None
        return best

    best = settle(TERMS)
    if hinged and best is not None and best[2].pose.fold * best[2].pose.roll > 0:  # a relief's
        # half width eases that fold (unfold_rolled.py): fitted again about a form's relief
        curves = [leaf.boundary, *leaf.veins]
        again = refolded(best[2], boundary, midrib, curves, first_axes, length, most, noise)
        again = [f for f in again if f[0] <= best[0] and checks.lies_flat(f[2], leaf)]
        best = checks.simplest(again, SIMPLER, CLOSE * length) if again else best
    if best is None or best[0] > TWIST_FROM * length:  # a twist, where the rest fall short
        twisted = settle(TWISTED)
        if twisted is not None and (best is None or twisted[0] <= TWIST_GAIN * best[0]):
            best = twisted
    if hinged:  # no fit bends about a relief as a form's, all four terms (unfold_mixed.py)
        starts = [placed(f[1], f[2], False)[0] for fits in plain.values() for f in fits[:1]]
        best = remixed(
            best, starts, leaf, boundary, midrib, first_axes, length, most, curls, before, noise
        )
    return None if best is None else best[2]
