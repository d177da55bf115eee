"""How far a pose may bend a blade and still be honoured (appreview31, findings 6 and 9).

A project's "bend" (sources/bend_entry.py) holds a pose's terms per unit of the leaf's
coordinates: the fold in degrees, the curl, the roll (a curvature) and the twist (radians per
unit). The sliders and `form` keep them to a range per blade (bend_sliders.RANGES: fold 75°,
curl 1 per the blade's length, a roll closing the blade into a tube, a twist of half a turn), but
a hand edit or another tool's units can hold any number: a fold of 89° shrank a blade to 0.83 of
its area, a roll of 1000 took 54 s and 5.9 GB and wrote a blade 7.5 times as large, a curl of 5
wrapped it past a full turn. `pose_trouble` says which term is past what the pose keeps, its
value and the range it may take on this blade, in the file's units.

Each limit is read off forms posed past the sliders as `Form.leaf` poses them (ovate, reniform,
linear, cordate reconstructed at grid 64: their mesh's area over the flat blade's):

- fold, FOLD each way: folded up, 0.980-1.008 of the area to 80° (82°: reniform 0.958; 85°:
  0.925-1.007; 88°: 0.86-0.89; 89°: 0.82-0.83, appreview31's s15); folded down the area grows
  from the sliders' own end (-75°: 1.008-1.034, -80°: 1.013-1.076, -85°: 1.04-1.12). 80° leaves
  room past the sliders' 75° for a pose fitted to a leaf folded there (unfold.py fits ovate
  folded -75° as -75.03°), and unfold.py fits no farther.
- curl, the midrib's turn 2 |curl| x up to MOST_TURN (0.95 of a half turn) at the blade's
  farthest x: past half a turn a curl is not undone (bend.Pose clips it). A curl of 1.5 per the
  length (3 radians) keeps 1.008-1.051 of the area, against 1.006-1.034 at the sliders' 1; at 2
  (4 radians) the linear blade keeps 0.82.
- roll, the widest margin's turn |roll| w (w the half width) up to ROLL_SHARE of a half turn,
  the closed tube (the sliders' 1), which keeps 0.997-1.000 of the area: Pose.apply turns no
  point past half a turn (bend._wrapped), so a roll past it lays the margins beyond on the
  tube's seam. The limit was 1.01, which lost that strip without a word: a linear blade rolled
  1.01 half turns kept 0.988 of its area, against 0.998 as a tube (1.05: 0.942-0.984). A leaf's
  pose as given (a project, the API's) is still taken to SAVED_ROLL_SHARE, 1.01: the app kept a
  tube's roll when a sketch edit widened the blade under 1%, and saved it so.
- twist, |twist| x at the apex up to TWIST_TURNS half turns: a twist keeps no size (the sliders'
  half turn gives reniform 1.41 of its area, linear 1.004; a full turn 2.16 and 1.010), but it
  is undone at any angle; a full turn holds a twisted grass blade's.

A blade's measures are read so that a term the curves were not bent by (a hand edit) cannot
hide: its flat blade (the pose's `flatten`) squeezes into the turn the term allows (a roll of
1000 lays any blade within pi / 1000 of its midrib), so the relief's (the flat blade's own, kept
in the project), the midrib's length as stored (every term keeps it, a twist to a few per cent)
and, for a pose without a relief (whose half width the relief would hold), the margin's reach
across the midrib with the roll's later terms undone count too, the largest of each. Across
only: its distance from the midrib counted the blade's own heights, and a wavy form rolled into a
tube by the sliders (cordate, wave 0.2, roll 1) read 1.41 half turns and its project was refused;
and across alone, undone without the roll, a fold leaves it off too (hastate, wave 0.2, folded
75° and rolled 1: 1.08 half turns).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from leafstudio.core.bend import Pose
from leafstudio.core.placed import PlacedPose, fitted
from leafstudio.errors import LeafError

FOLD = 80.0  # degrees each way (module docstring)
MOST_TURN = 0.95 * np.pi  # radians the curl may turn the midrib through at the blade's end
ROLL_SHARE = 1.0 + 1e-9  # half turns the roll may turn the widest margin through: the tube
# (Pose.apply turns no point past it), to the round-off of the blade's measures
SAVED_ROLL_SHARE = 1.01  # ... and a leaf's pose as given (a project, `flat` False): the limit
# before, to which the app kept a tube's roll when a sketch edit widened it (eased_roll eased
# only past it), so the projects it saved reopen (a tube widened 0.5%: 1.005, refused by ROLL_SHARE)
TWIST_TURNS = 2.0  # half turns the twist may turn the apex against the base
SEAM_SHARE = 0.99  # half turns a folded or twisted blade's widest margin may roll through
# (`tube_share`): closed to its seam, a tube folded or twisted however little passes its sheet
# through itself there (crossing face pairs of the mesh at grid 128, open3d: ovate rolled 1 and
# folded 75 68, folded 1 82, twisted 0.1 37; cordate folded 75 7; linear 5,875), rolled 0.999 or
# 0.99 none (ovate, linear, hastate; /work/notes/bowls38/sweep_cross.py): eased to it
# a pose fitted to curves in 3D (core/unfold.py, its relief on the margin's plane) was searched
# to 85° each way before FOLD: the projects the app saved then reopen, their fit reproducing
# the curves they were fitted to
FITTED_FOLD = 85.0
CURL_SEARCH = 1.5  # the curl core/unfold.py searches to, each way, over the bent outline's
# diagonal: a strongly curled leaf's diagonal is short, and its fit turned the midrib 3.02
# radians, past MOST_TURN (review31: cordate curled 1.5, three forms 1.7); or, where more, the
# curl that turns the midrib, as long as it stands, through MOST_TURN: a blade wider than long
# has a diagonal the curl leaves long (reniform curled 1, 1.389 wide: 1.5 over its diagonal
# was 0.88 of the curl its margin takes about the margin's plane, and a roll across it was fitted)
FIT_POINTS = 60  # the margin and the midrib thinned to about this many points each for the fit
SEARCH_SLACK = 1.05  # a fit at its search's end, re-posed by a sketch edit, still reopens


def fit_bounds(boundary: np.ndarray, midrib: np.ndarray) -> tuple[float, float, float, float]:
    """What core/unfold.py searches a pose over for curves in 3D, the (n, 3) `boundary` and
    the (m, 3) `midrib` (either end first) as given: the largest curl (CURL_SEARCH over the
    outline's diagonal, or MOST_TURN over twice the midrib's length where more: any curl the
    loader takes of a blade of that midrib is within it) and roll (a half turn of the margin's
    farthest point from the midrib's chord: the flat blade is at least as wide), then that
    diagonal and that farthest reach, over the curves thinned to FIT_POINTS as the fit takes
    them."""
    length = np.linalg.norm(np.ptp(boundary, axis=0))  # numpy's: 0 divides to inf, not raises
    along = np.linalg.norm(np.diff(midrib, axis=0), axis=1).sum()  # a curl keeps its length
    boundary = boundary[:: max(1, len(boundary) // FIT_POINTS)]
    origin = midrib[0]
    chord = (midrib[-1] - origin) / np.linalg.norm(midrib[-1] - origin)
    points = boundary - origin
    reach = np.linalg.norm(points - np.outer(points @ chord, chord), axis=1).max()
    curl = max(CURL_SEARCH / length, MOST_TURN / (2 * along))
    return float(curl), float(np.pi / reach), float(length), float(reach)


def fit_like(bend: Any) -> bool:
    """Whether `bend` may be a pose core/unfold.py fitted to curves in 3D, which the app saves
    as it found it: a PlacedPose whose relief is on the margin's plane (placed.fitted), or has
    none (a fit past unfold.HINGE_SIZES: ovate curled 1.7 was fitted a curl turning its midrib
    3.11 radians). A drawn leaf's, bent by the sliders, has its sketch's relief."""
    return fitted(bend) or (
        isinstance(bend, PlacedPose) and getattr(bend.pose, "relief", 0) is None
    )


class PoseRefused(LeafError):
    """`check_pose`'s refusal, with what a caller in other units needs to say it in its own
    (the app's sliders, gui/model/bending.py: its message gave a roll per unit of the leaf's
    coordinates, closing32): the `term` ("fold", "curl", "roll" or "twist"), its `value` and
    the `most` it may take on this blade, both in the pose's units."""

    def __init__(self, message: str, term: str, value: float, most: float) -> None:
        super().__init__(message)
        self.term, self.value, self.most = term, value, most


def pose_trouble(
    bend: Any, boundary: np.ndarray, veins: list[np.ndarray], flat: bool = False
) -> str | None:
    """What of `bend` (a bend.Pose, or a placed.PlacedPose in its frame) a blade whose (n, 3)
    `boundary` and (m_i, 3) `veins` are bent by it (as a project holds them; `flat`: the flat
    blade it is about to bend) cannot take, in one line: the term, its value and the range
    allowed on this blade, in the file's units. None when every term holds, or for a bend that
    is no pose (a scan's sheet)."""
    trouble = _trouble(bend, boundary, veins, flat)
    return None if trouble is None else trouble[0]


def _trouble(
    bend: Any, boundary: np.ndarray, veins: list[np.ndarray], flat: bool
) -> tuple[str, str, float, float] | None:
    """`pose_trouble`'s line, the term, its value and the most it may take (`PoseRefused`)."""
    pose = getattr(bend, "pose", bend)
    if not isinstance(pose, Pose):
        return None
    most_fold = FITTED_FOLD if fit_like(bend) else FOLD
    if abs(pose.fold) > most_fold:
        says = (f'"fold" {pose.fold:g} is past what a fold keeps of the blade; a fold is taken '
                f"from -{most_fold:g} to {most_fold:g} degrees")  # fmt: skip
        return says, "fold", pose.fold, most_fold
    reach, half = blade_measures(bend, boundary, veins, flat)
    rolls = ROLL_SHARE if flat else SAVED_ROLL_SHARE  # a pose asked for, or one as given
    per_unit = "per unit of the leaf's coordinates"
    terms = (
        ("curl", 2 * pose.curl * reach, MOST_TURN / (2 * reach), f"{per_unit}) turns its "
         f"midrib, {reach:.3g} long, through {{turn:.3g}} radians; a curl is taken up to "
         f"{MOST_TURN:.3g} radians (under half a turn)"),
        ("twist", pose.twist * reach / np.pi, TWIST_TURNS * np.pi / reach, f"radians {per_unit})"
         f" turns its apex, {reach:.3g} from its base, through {{turn:.3g}} half turns; a twist "
         f"is taken up to {TWIST_TURNS:g} half turns"),
        ("roll", pose.roll * half / np.pi, rolls * np.pi / half, f"{per_unit}) rolls its "
         f"margins, {half:.3g} from its midrib, through {{turn:.4g}} half turns; a roll is taken "
         f"up to {rolls:.3g} (a closed tube{'' if flat else ', widened by a sketch edit'})"),
    )  # fmt: skip
    searched = {}  # a fitted pose's: what the fit searched, which the app saved
    if fit_like(bend) and len(veins) and len(veins[0]) > 1:
        curves = [np.asarray(c, dtype=float) for c in (boundary, veins[0])]
        with np.errstate(all="ignore"):  # a degenerate blade's bounds: none (nan) or inf
            # read on the bent curves, as the loader reads them (a flat blade's diagonal is
            # longer than the curled one the fit searched over)
            bounds = fit_bounds(*[bend.apply(c) for c in curves] if flat else curves)[:2]
        pairs = zip(("curl", "roll"), bounds, strict=True)
        searched = {k: SEARCH_SLACK * b for k, b in pairs if b < np.inf}
    for name, turn, most, says in terms:
        most = max(most, searched.get(name, 0.0))
        value = getattr(pose, name)
        if value != 0 and not abs(value) <= most:  # not: a reach of 0 gives nan
            return (f'"{name}" {value:g} ({says.format(turn=abs(turn))}: from {-most:.3g} to '
                    f"{most:.3g} on this blade", name, value, most)  # fmt: skip
    return None


def check_pose(
    bend: Any, boundary: np.ndarray, veins: list[np.ndarray], flat: bool = False
) -> None:
    """Refuse `bend` where a pose enters other than from a file (sources/bend_entry.py names
    the file): the pipeline's leaf (core/pipeline.py: `ls.reconstruct`, `Leaf(..., bend=...)`),
    a project about to be saved, the app's sliders (gui/model/bending.py, on the `flat` blade).
    Before, only loading was guarded: `Pose(fold=89)` through the API or the app was taken and
    kept 0.83 of the blade's area, silently.

    Raises
    ------
    PoseRefused
        A LeafError naming the term, its value and the range it may take on this blade
        (`pose_trouble`).
    """
    trouble = _trouble(bend, boundary, veins, flat)
    if trouble is not None:
        raise PoseRefused(f"the leaf's bend: {trouble[0]}", *trouble[1:])


def tube_share(fold: float, twist: float) -> float:
    """The half turns a pose of this `fold` and `twist` may roll the blade's widest margin
    through: the closed tube (ROLL_SHARE), kept SEAM_SHARE of it when folded or twisted."""
    return ROLL_SHARE if fold == 0 and twist == 0 else SEAM_SHARE


def seam_note(roll: float, fold: float, twist: float) -> str:
    """What a pose asked to roll its widest margin `roll` half turns (a form's, the sliders'
    share) and fold `fold` and twist `twist` says when `eased_roll` keeps it off its seam
    (SEAM_SHARE), "" when its roll is taken as asked: `form` said so, the app's Roll slider
    went back from 1 to 0.99 without a word. A roll at the seam to rounding is taken as asked
    (the sliders' 0.99 came back from the pose's units 1 ulp over at 257 of 2000 half widths)."""
    if abs(roll) <= tube_share(fold, twist) + 1e-9:
        return ""
    how = "folded" if fold else "twisted"
    return (
        f"roll {roll:g} eased to {np.copysign(SEAM_SHARE, roll):g}: a tube closed to its seam "
        f"and {how} would pass through itself there"
    )


def eased_roll(pose: Pose, half: float) -> Pose:
    """`pose` with a roll that turns the blade's widest margin, `half` from the midrib in the
    pose's units, past `tube_share` of a half turn eased to it: a sketch edit keeps the pose per
    the blade's length (gui/model/bending.py), so a tube made 20% wider rolled its margins 1.2
    half turns, into itself, and its project was refused; and a tube closed to its seam, folded
    or twisted, passed its sheet through itself there (SEAM_SHARE): a form's (forms/make.py),
    the sliders' (bending.posed)."""
    most = np.pi / half if half > 0 else np.inf
    share = tube_share(pose.fold, pose.twist)
    if abs(pose.roll) <= share * most:
        return pose
    eased = most if share == ROLL_SHARE else share * most
    return replace(pose, roll=float(np.copysign(eased, pose.roll)))


def blade_measures(
    bend: Any, boundary: np.ndarray, veins: list[np.ndarray], flat: bool = False
) -> tuple[float, float]:
    """The blade's reach along its midrib (its farthest x from the base: how far a curl and a
    twist turn it) and its half width (how far a roll turns its margins) in the pose's
    coordinates, from the (n, 3) `boundary` and (m_i, 3) `veins` that `bend` (a Pose or a
    PlacedPose) bends (`flat`: the flat blade, read as it is, not flattened); each the largest
    of its flat blade's, its relief's and, as stored, the midrib's length or, without a relief,
    the margin's reach across it with the roll's later terms undone (module docstring). 1 for a
    blade with no extent, which the loader refuses on its own. Given flat, a roll past the tube
    is read as it is: flattened, a pose without a relief lays its margins on the tube's seam
    (bend._wrapped turns no point past half a turn) and read 1.0 for a blade rolled 1.2."""
    pose, frame = getattr(bend, "pose", bend), getattr(bend, "frame", None)

    def blade(points: np.ndarray) -> np.ndarray:
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        return points if frame is None else np.column_stack(frame.to_plane(points))

    stored = blade(boundary)
    midrib = blade(veins[0]) if len(veins) else np.zeros((0, 3))
    if flat:
        laid = rolled = stored
    else:
        with np.errstate(all="ignore"):
            laid = pose.flatten(stored)
            rolled = replace(pose, roll=0.0).flatten(stored) if pose.roll != 0 else laid
    relief = pose.relief
    reach = _largest(
        np.abs(laid[:, 0]),
        np.linalg.norm(np.diff(midrib, axis=0), axis=1).sum(keepdims=True),
        np.abs([relief.knots[0], relief.knots[-1]]) if relief is not None else [],
    )
    half = _largest(
        np.abs(laid[:, 1]),
        np.abs(rolled[:, 1]) if relief is None else [],
        [relief.half_width] if relief is not None else [],
    )
    return reach or 1.0, half or 1.0


def _largest(*values: Any) -> float:
    """The largest finite value of any of the arrays, else 0."""
    finite = [v[np.isfinite(v)] for v in (np.asarray(a, dtype=float).ravel() for a in values)]
    return max((float(v.max()) for v in finite if len(v)), default=0.0)
