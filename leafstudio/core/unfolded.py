"""A leaf given in 3D with the bend that lays it flat (core/unfold.py), found once per curves.

Curves found to need no bend are remembered (UNBENT_KEPT of them, by their bytes): a file's leaf
is unfolded when opened (workflows.open_file) and again by its Pipeline, and a waved blade,
fitted and refused, took 0.5-1.4 s of CPU each time.

A curl fitted alone about the margin's plane is re-expressed about the flat midrib's mean height
(`levelled`), as a form's and the app's curls bend a blade: the margin's flatness cannot tell
the two apart, and about the margin's plane the curl stretched the midrib (posed forms written as
CSVs and read back: ovate curled 0.8 came back 1.064 long, lanceolate 0.6 1.018, cordate 0.5
1.036; now 0.999, 1.000, 0.999; /work/notes/poses32/csv_traits.py). So is a curl whose margin
lies on the level's inner side (a curl down, the midrib over the margin), which the curl carries
there along an exponential (bend._rolled_radius): about the same axis the margin lies on one
circle still, and flat, a little under the margin's plane. It was left as fitted: ovate curled
-0.8, read from its CSV, was fitted -0.853 and measured 0.938 long (exp(-2 curl L) of the
length, L its level), reniform curled -1 0.882 long at the fit's pose; now -0.799 and 1.001
(/work/notes/curl35).

A document in the app whose curves no pose laid flat (`unposed_share`) keeps that refusal for its
sketch edits, whose curves are new bytes: gui/model/bending.keeps_refusal has each run's leaf
taken `as_given`. A cup 0.142 of its width off its plane had paid a refused fit, 2.1-2.7 s of
CPU, at every edit (/work/notes/bowls38/cup_edit_probe.py).
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from dataclasses import replace

import numpy as np

from leafstudio.core.bend import flat_leaf
from leafstudio.core.placed import PlacedPose
from leafstudio.core.pose_limits import pose_trouble
from leafstudio.core.pose_relief import margin_relief
from leafstudio.core.unfold import fit_pose
from leafstudio.core.unfold_checks import bent, off_plane
from leafstudio.model import Leaf

UNBENT_KEPT = 32  # curves remembered as needing no bend
LEVEL_ROUNDS = 3  # `levelled`: each round reads the level off the blade the last laid flat (ovate
# curled 0.8: curl 0.7516, then 0.8010, 0.8010)
OFF_FLAT = 1e-2  # a fitted pose that leaves the margin farther off flat than this share of the
# outline's diagonal (rms) is warned of (`off_flat`): the 44 poses fitted to the 49 rows of
# /work/notes/pose37/repro.py and session 38's two (ovate folded 60, twisted 0.2 or curled 0.5
# and rolled 0.3) leave 1e-10-5.8e-3 (oblanceolate rolled -1; reniform curled -1 2.4e-3), ovate
# folded 75 and twisted 0.2, fitted fold -31.1 and curl 1.08 (0.633 wide), 1.46e-2
# (/work/notes/offflat38/measure.py)
_UNBENT: OrderedDict[bytes, None] = OrderedDict()
_UNBENT_LOCK = threading.Lock()  # pipelines run on worker threads too


def unfolded(leaf: Leaf) -> Leaf:
    """`leaf` with the bend `fit_pose` finds for it; the leaf itself when none is needed (and
    then remembered: the module docstring)."""
    if leaf.bend is not None:
        return leaf
    key = _key(leaf)
    with _UNBENT_LOCK:
        if key in _UNBENT:
            return leaf
    bend = fit_pose(leaf)
    if bend is not None:
        return Leaf(leaf.boundary, leaf.veins, bend=levelled(bend, leaf))
    _remember(key)
    return leaf


def pose_note(leaf: Leaf) -> str:
    """What a reader of `leaf` is told of its fitted pose: that it could not be read reliably
    when it leaves the margin more than OFF_FLAT off flat (`off_flat`); "" otherwise, and for a
    leaf without a bend (a pose given, not fitted, leaves it flat to rounding). The pipeline's
    result says it (Pipeline._frame_notes), so the commands and the window do: a warning from
    the fit alone went unseen (the command line ignores warnings)."""
    if not isinstance(leaf.bend, PlacedPose):  # unbent, or a form's Pose: given, not fitted
        return ""
    share = off_flat(leaf.bend, leaf)
    if share <= OFF_FLAT:
        return ""
    return (
        f"the leaf's pose could not be read reliably from its 3D curves: the pose fitted leaves "
        f"its margin {share:.1%} of its size off flat, so its flat blade (length, width, area) "
        f"may be distorted; a leaf saved as .leaf.json keeps its own pose"
    )


def as_given(leaf: Leaf) -> Leaf:
    """`leaf`, remembered as needing no bend: `unfolded` (its Pipeline's) fits it none. For the
    app's edits of a document whose curves no pose laid flat (gui/model/bending.keeps_refusal)."""
    if leaf.bend is None:
        _remember(_key(leaf))
    return leaf


def refit(leaf: Leaf) -> Leaf:
    """`leaf`'s curves without a bend, forgotten as needing none: `unfolded` (its Pipeline's)
    fits them again. A new Leaf, so that a pipeline kept for `leaf` (the app's worker keeps the
    last) is not reused. For the app's Fit pose again, which a remembered refusal would
    otherwise answer at once (gui/model/pose_fits.py)."""
    with _UNBENT_LOCK:
        _UNBENT.pop(_key(leaf), None)
    return Leaf(leaf.boundary, leaf.veins)


def unposed_share(leaf: Leaf) -> float | None:
    """How far `leaf`'s margin lies off its PCA plane (RMS, share of its RMS width, as
    unfold_checks.OFF_PLANE counts it) when it is bent in 3D and `unfolded` finds no pose that
    lays it flat (a cup); None when it has a bend, is flat or a pose is found for it."""
    if leaf.bend is not None or unfolded(leaf) is not leaf or not stands_unposed(leaf):
        return None
    return plane_share(leaf)


def plane_share(leaf: Leaf) -> float:
    """`leaf`'s margin's RMS distance off its PCA plane, per its RMS width (unfold_checks)."""
    rms, width = off_plane(np.asarray(leaf.boundary, dtype=float))
    return rms / width if width > 0 else 0.0


def off_flat(bend: PlacedPose, leaf: Leaf) -> float:
    """How far `bend` leaves `leaf`'s margin off its flat plane: RMS height over the outline's
    diagonal. A pose fitted wrong lies flat elsewhere (unfold_checks.lies_flat) but not here."""
    height = bend.frame.to_plane(bend.flat_curve(leaf.boundary, ring=True))[1]
    size = float(np.linalg.norm(np.ptp(np.asarray(leaf.boundary, dtype=float), axis=0)))
    return float(np.sqrt(np.mean(height**2))) / size if size > 0 else 0.0


def _key(leaf: Leaf) -> bytes:
    """The bytes of `leaf`'s curves, hashed: what `_UNBENT` remembers."""
    digest = hashlib.blake2b(digest_size=16)
    for curve in (leaf.boundary, *leaf.veins):
        digest.update(np.ascontiguousarray(curve, dtype=float).tobytes() + b"|")
    return digest.digest()


def _remember(key: bytes) -> None:
    """Remember curves of `key` as needing no bend (the newest UNBENT_KEPT)."""
    with _UNBENT_LOCK:
        _UNBENT[key] = None
        _UNBENT.move_to_end(key)
        while len(_UNBENT) > UNBENT_KEPT:
            _UNBENT.popitem(last=False)


def levelled(bend: PlacedPose, leaf: Leaf) -> PlacedPose:
    """`bend`, fitted to `leaf`'s curves, with a curl fitted alone about the margin's plane (no
    relief: its level 0) bent instead about the flat midrib's mean height L (margin_relief's
    hinge, Relief.posed_level), as a form's curl keeps its midrib's length: the same axis, its
    radius 1 / (2 curl) less L. The margin's points then lie where they did (the pose's
    flatten undone), flat: on the margin's plane where the curl carries heights below the level
    linearly (bend._rolled_radius: curl and L of one sign), else on the circle of radius
    R exp(-L / R) about that axis, which lays them flat L² / (2 R) or so under it (ovate curled
    -0.8: 1.3e-3 of the length). For any other pose, and where the curl so found is past what the
    loader takes of a fit (core/pose_limits.py: ovate curled 1.7, fitted 3.11 radians of turn,
    would turn 3.16), `bend` as it is."""
    pose = bend.pose
    if pose.relief is not None or pose.curl == 0 or (pose.fold, pose.roll, pose.twist) != (0, 0, 0):
        return bend
    levelled = bend
    for _ in range(LEVEL_ROUNDS):
        flat = flat_leaf(Leaf(leaf.boundary, leaf.veins, bend=levelled))
        blade = [np.column_stack(bend.frame.to_plane(c)) for c in (flat.boundary, *flat.veins)]
        relief = margin_relief(blade[0], blade[1:])
        if relief is None:
            return bend
        level = relief.posed_level(replace(pose, curl=0.0, relief=relief))
        curl = pose.curl / (1 - 2 * pose.curl * level)
        levelled = PlacedPose(replace(pose, curl=curl, relief=relief), bend.frame)
    past = pose_trouble(levelled, leaf.boundary, list(leaf.veins)) is not None
    return bend if past else levelled


def unposed_hint(leaf: Leaf) -> str:
    """What to add to a refusal of `leaf` as `unfolded` left it: when its margin stands bent in
    3D (unfold_checks.bent, the test before a pose is fitted) and no bend lays it flat (none
    given, none fitted), that it may be a posed or scanned leaf written without its pose or
    sheet (a lanceolate form twisted 1, saved as .csv, was refused with "vein 1: 2 of 49 points
    lie outside the boundary" and no word of why); "" otherwise."""
    if not stands_unposed(leaf):
        return ""
    return (
        "; the leaf is bent in 3D and no pose lays it flat: a posed or scanned leaf saved as a "
        "point list keeps neither its pose nor its sheet (its .leaf.json does)"
    )


def stands_unposed(leaf: Leaf) -> bool:
    """Whether `leaf` has no bend and its margin stands bent in 3D (unfold_checks.bent): a pose
    may be fitted to it (the app's Fit pose again, gui/model/pose_fits.py). 0.03 ms for the cup's
    502 margin points."""
    midrib = np.asarray(leaf.veins[0], dtype=float) if leaf.veins else None
    return leaf.bend is None and bent(np.asarray(leaf.boundary, dtype=float), midrib)
