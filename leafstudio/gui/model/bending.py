"""A leaf bent live in the app (issue 21, build item 6): the fold and curl sliders set a
`core.bend.Pose` on the document's leaf, as one undo step per drag.

The document keeps the flat blade's sketch (the editor draws the blade); its leaf is the
sketch's leaf bent by the pose about its midrib (`core.placed.PlacedPose`), so the pipeline
reconstructs the flat blade and bends the mesh, and Save writes the pose (sources/files.py). A
form keeps its own `Pose` (its blade coordinates are the world's, the form 1 long). The session's
curl, roll and twist are per the blade's length (`in_lengths`); the sliders show the roll and
twist in the Forms dock's terms (gui/qt/bend_sliders.py, `blade_half_width`). A sketch edit bends
the new leaf by the same pose, about the midrib as it is now; a pose fitted to curves in 3D keeps
its frame and relief, its hinge moved with the midrib (`keeps_fit`, `rehinged`), and either way
the sliders' figures stay.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import shapely

from leafstudio.core.bend import Pose, flat_leaf
from leafstudio.core.placed import PlacedPose, blade_frame, fitted
from leafstudio.core.pose_limits import TWIST_TURNS, PoseRefused, check_pose, eased_roll
from leafstudio.core.pose_relief import margin_relief, relief_of
from leafstudio.core.unfolded import plane_share
from leafstudio.errors import LeafError
from leafstudio.gui.model.history import State, Step
from leafstudio.model import Bend, Leaf

FLAT = Pose()
REFIT = 1.25  # `keeps_refusal`: an edited leaf this many times as far off its plane as the
# curves refused a pose is fitted again (an edit of the cup 0.6 deep, 0.142 off as opened, left
# its derived sketch's curves 0.126 off: the sketch's spline, not the user, moved them)


def pose_of(leaf: Leaf | None) -> Pose:
    """The pose the leaf is bent by, as the sliders set it (a flat Pose for none, or a bend the
    sliders cannot show): a leaf bent about its midrib has its curl, roll and twist per its
    blade's length (`in_lengths`)."""
    bend = None if leaf is None else leaf.bend
    if isinstance(bend, PlacedPose):
        return in_lengths(bend.pose, blade_extent(bend.flat_curve(leaf.boundary, True), bend.frame))
    return bend if isinstance(bend, Pose) else FLAT


def blade_extent(boundary: np.ndarray, frame: Any) -> float:
    """The flat blade's length from base to apex, from its (n, 3) flat `boundary`, as a form's
    is (forms/make.Form: its curl and twist are per base to apex, lobes behind the base, a
    cordate or sagittate blade's, not counted): from where the midrib's line (`frame.u` through
    `frame.origin`, core/placed.blade_frame) enters the outline at the base to the outline's
    farthest reach along u. Its reach, not the line's piece inside the outline: a curved
    (falcate) blade's chord leaves it (a 60° bow kept a third of its length, and bent it three
    times too hard; review). The outline's whole extent along u when the line misses it."""
    if not len(boundary):
        return 1.0
    offset = np.asarray(boundary, dtype=float) - frame.origin
    along, across = offset @ frame.u, offset @ frame.v
    extent = float(np.ptp(along))
    outline = shapely.Polygon(np.column_stack([along, across]))
    outline = outline if outline.is_valid else outline.buffer(0)
    line = shapely.LineString([(along.min() - 1.0, 0.0), (along.max() + 1.0, 0.0)])
    cut = line.intersection(outline)
    pieces = [piece for piece in getattr(cut, "geoms", [cut]) if piece.length > 0]
    if not pieces:
        return extent if extent > 0 else 1.0
    base = min(pieces, key=lambda piece: piece.distance(shapely.Point(0.0, 0.0)))
    length = float(along.max()) - min(base.bounds[0], 0.0)
    return length if length > 0 else (extent if extent > 0 else 1.0)


def blade_half_width(leaf: Leaf | None, plane: Any = None) -> float:
    """The flat blade's widest reach across its midrib, per its length (the sliders' units,
    `pose_of`): a roll of π over it closes the blade into a tube, as a form's roll of 1 does
    (forms/make.Form.leaf). A form bent by its own Pose is in its blade's coordinates, 1 long;
    any other leaf is read in its blade frame on `plane` (a sketch's Frame), as `posed` bends
    it. 1 without a leaf or a width."""
    if leaf is None:
        return 1.0
    flat = flat_leaf(leaf)
    if isinstance(leaf.bend, Pose):
        half = float(np.abs(flat.boundary[:, 1]).max())
    else:
        try:
            bend = leaf.bend
            frame = bend.frame if isinstance(bend, PlacedPose) else blade_frame(flat, plane)
        except LeafError:  # no plane given, and a leaf on one line has none of its own
            return 1.0
        across = (flat.boundary - frame.origin) @ frame.v
        half = float(np.abs(across).max()) / blade_extent(flat.boundary, frame)
    return half if np.isfinite(half) and half > 0 else 1.0


def _same_pose(a: Pose, b: Pose) -> bool:
    """The same fold, curl, roll and twist to round-off: a slider's roll, its share times π
    over the half width, came back from the leaf 12 digits long (`in_lengths`), and a release
    at the same place reconstructed the leaf once more."""
    terms = ("fold", "curl", "roll", "twist")
    return bool(
        np.allclose([getattr(a, t) for t in terms], [getattr(b, t) for t in terms], rtol=1e-9)
    )


POSE_TERMS = ("fold", "curl", "roll", "twist")  # the sliders' terms, the Forms dock's too


def term_units(half_width: float) -> dict[str, float]:
    """A slider's figure times this is the Pose's term: the roll's half turn over the blade's
    half width (`blade_half_width`), the twist's half turn; fold and curl as they are."""
    return {"fold": 1.0, "curl": 1.0, "roll": np.pi / half_width, "twist": np.pi}


def pose_terms(pose: Pose, half_width: float) -> dict[str, float]:
    """`pose` in the sliders' terms (the Forms dock's, forms/terms.RELIEF): the fold in degrees,
    the curl per length, the roll as the share of a half turn at the widest, the twist in half
    turns."""
    units = term_units(half_width)
    return {name: getattr(pose, name) / units[name] for name in POSE_TERMS}


def terms_pose(
    terms: dict[str, float], half_width: float, shown: tuple[Pose, dict[str, float]] = (FLAT, {})
) -> Pose:
    """The pose the sliders' `terms` ask for. A term still at the figure `shown` set (the pose
    shown, and the figures its widgets took) keeps that pose's own value to the bit, not its
    figure through the units and back (a slider's 2 decimals: a curl of 0.4996 read 0.5)."""
    pose, figures = shown
    units = term_units(half_width)
    return Pose(
        **{
            name: getattr(pose, name) if figures.get(name) == value else value * units[name]
            for name, value in terms.items()
        }
    )


# what a slider's figure counts, said after a refused figure's range (forms/terms.RELIEF)
TERM_UNITS = {
    "fold": "degrees",
    "curl": "per the blade's length: 1 turns its apex 2 radians",
    "roll": "half turns of the widest margins: 1 closes the blade into a tube",
    # a figure per the blade's length, the limit at the apex, which may lie short of it (-2.11
    # to 2.11 read as turning the apex past the limit's 2: review33)
    "twist": f"half turns per the blade's length: its apex may turn through {TWIST_TURNS:g}",
}


def refusal(exc: PoseRefused, pose: Pose, half_width: float) -> str:
    """A pose refused past the limits (core/pose_limits.check_pose), said in the sliders' terms
    (the Forms dock's): the term as its slider names it, the figure asked and the range this
    blade takes. The limits' own line gave a roll and a twist per unit of the leaf's
    coordinates (closing32). The figures scale as the pose's terms do (`term_units`, and
    `in_lengths` for a leaf in its own units), so the range is the figure's share of it."""
    asked = pose_terms(pose, half_width)[exc.term]
    most = abs(asked * exc.most / exc.value) if exc.value else exc.most
    name = exc.term.capitalize()
    return (
        f"{name} {asked:.3g} is more than this blade takes: {name} goes from {-most:.3g} to "
        f"{most:.3g} on it ({TERM_UNITS[exc.term]})."
    )


def bend_text(pose: Pose, half_width: float) -> str:
    """A bend's undo text in the sliders' terms (the Forms dock's): the roll as the share of a
    half turn at the widest, the twist in half turns."""
    terms = pose_terms(pose, half_width)
    return (
        f"Bend: fold {pose.fold:g}°, curl {pose.curl:g}"
        + (f", roll {terms['roll']:.3g}" if pose.roll else "")
        + (f", twist {terms['twist']:.3g}" if pose.twist else "")
    )


def in_lengths(pose: Pose, length: float) -> Pose:
    """`pose` (per unit of the leaf's coordinates) per `length` instead: the session's curl, roll
    and twist are per the blade's length (a curl of 1 turns the apex 2 radians, whatever the
    units: a drawn leaf 80 mm long, curled 1 per mm, wrapped round 160 radians)."""

    def scaled(value: float) -> float:  # 12 digits: a curl of 0.3 reads back as 0.3
        return float(f"{value * length:.12g}")

    return replace(pose, curl=scaled(pose.curl), roll=scaled(pose.roll), twist=scaled(pose.twist))


def can_pose(leaf: Leaf | None) -> bool:
    """Whether the sliders may bend this leaf: it is flat or bent by a pose. A scan bent by the
    sheet fitted to its points (core/sheet.py) is not: a pose would replace that fit."""
    return leaf is not None and (leaf.bend is None or isinstance(leaf.bend, (Pose, PlacedPose)))


def sheet_tip(scan_open: bool, sliders: bool = False) -> str:
    """Why the pose terms (the Forms dock's boxes, or the Parameters panel's `sliders`) are off
    for a leaf bent by a scan's sheet (`can_pose`): the scan open, or a leaf saved from one (a
    project keeps the sheet, not the scan's points). Both said "This scan" for a saved project
    too (closing32)."""
    who = (
        "This scan is bent by the smooth sheet fitted to its points"
        if scan_open
        else "This leaf, saved from a scan, is bent by the smooth sheet fitted to that scan's "
        "points"
    )
    if sliders:
        return f"{who}; a fold or curl would replace that fit, so the sliders are off for it."
    return (
        f"{who}: no fold, curl, roll or twist applies to it (a pose would replace that fit). A "
        "shape picked in the gallery starts unbent."
    )


def posed(
    flat: Leaf | None, pose: Pose, like: Bend | None = None, plane: Any = None, check: bool = False
) -> Leaf | None:
    """The flat blade `flat` bent by `pose`: as a form is when `like` (the bend it had) is a
    plain Pose, else about its midrib on `plane` (a sketch's Frame; without one, `like`'s own
    frame and relief when it is a PlacedPose, `flat` being its flat blade, else the boundary's
    PCA plane); either way about the blade's own relief (core/pose_relief.py: a fold turns each
    half about the midrib as it stands). The flat pose gives `flat` itself, without a bend.
    `check`: a pose asked for (`Bending.set_bend`), refused past what it keeps of this blade
    (pose_limits.check_pose, a LeafError) rather than a widened tube's roll eased."""
    if flat is None or pose == FLAT:
        return flat
    # a pose without a relief (a project saved before reliefs; curves in 3D unfolded at over
    # 1e100, core/unfold.py) keeps bending about the margin's plane: a slider's nudge of 1e-6°
    # moved an unfolded ovate's outline 0.157 of its length when it took the blade's relief
    like_relief = getattr(getattr(like, "pose", like), "relief", 0)
    about_relief = like_relief is not None
    # a pose fitted to curves in 3D folds about the flat midrib over the margin's plane: about
    # the blade's relief instead, a nudge of the roll moved a rolled ovate's outline 5e-2
    own_relief = margin_relief if getattr(like_relief, "on_margin", False) else relief_of
    if isinstance(like, Pose):  # a form's blade is in its own coordinates
        relief = own_relief(flat.boundary, flat.veins) if about_relief else None
        half = float(np.abs(flat.boundary[:, 1]).max())  # a widened tube stays one
        bend: Bend = _eased(replace(pose, relief=relief), half, flat, check)
    else:  # bent about the blade's own relief, read in its frame (core/pose_relief.py)
        # `flat` re-posed (no sketch's plane: set_bend on `like`'s flat blade) keeps its bend's
        # frame and relief. Found again, a fitted pose's frame (core/unfold.py: its normal the
        # fit's) came back with fit_frame's normal, toward the veins: ovate folded 45 and curled
        # 0.5, fitted -45 about a normal down, flipped over for a nudge of 1e-6 (its outline
        # moved 0.90 of its length); and its relief, read again from the flat midrib, is not the
        # fit's (whose hinge is the midrib flattened about the round before's: unfold_hinge),
        # 7e-4 to 1.1e-3 off: ovate folded 60 and rolled 0.4 moved 0.015, 45 and 0.5 8e-4
        kept = like if plane is None and isinstance(like, PlacedPose) else None
        frame = blade_frame(flat, plane) if kept is None else kept.frame
        own = in_lengths(pose, 1.0 / blade_extent(flat.boundary, frame))

        def blade(points: np.ndarray) -> np.ndarray:
            return np.column_stack(frame.to_plane(points))

        relief = None
        if kept is not None:
            relief = kept.pose.relief
        elif about_relief:
            relief = own_relief(blade(flat.boundary), [blade(v) for v in flat.veins])
        half = float(np.abs(blade(flat.boundary)[:, 1]).max())
        asked = PlacedPose(replace(own, relief=relief), frame)
        bend = PlacedPose(_eased(asked, half, flat, check).pose, frame)
    return Leaf(bend.apply(flat.boundary), [bend.apply(v) for v in flat.veins], bend=bend)


def _eased(bend: Any, half: float, flat: Leaf, check: bool) -> Any:
    """`bend` (a Pose, or a PlacedPose) about to bend the flat blade `flat`, whose half width in
    its coordinates is `half`: refused past the limits when `check` (a pose asked for); its roll
    eased to the tube, or short of its seam when folded or twisted (pose_limits.eased_roll: a
    sketch edit keeps the pose; a fold of a closed tube passed its sheet through itself)."""
    if check:
        check_pose(bend, flat.boundary, list(flat.veins), flat=True)
    pose = eased_roll(getattr(bend, "pose", bend), half)
    return pose if isinstance(bend, Pose) else PlacedPose(pose, bend.frame)


def keeps_fit(like: Bend | None, before: Any, sketch: Any) -> bool:
    """Whether a sketch edit from the Sketch `before` to `sketch` keeps the bend `like`'s frame
    and relief: a pose fitted to curves in 3D (core/unfold.py: its relief on the margin's
    plane) while the sketch's plane is as it was (a moved midrib moves its hinge: `rehinged`).
    Its frame and relief are the fit's (the hinge the midrib flattened about the round
    before's: unfold_hinge); found again from the sketch's midrib (8 points of it:
    sketch_model.DERIVED_VEIN_POINTS) and plane, the first edit of ovate folded 60 and rolled
    0.4, opened from a CSV, moved its outline 0.018 of its length
    (test_a_fitted_leafs_first_sketch_edit_keeps_it_where_it_stood). A drawn leaf's relief is
    its sketch's heights, read again at every edit."""
    if not fitted(like):
        return False
    if before is None or not (len(before.veins) and len(sketch.veins)):
        return False
    return all(
        np.array_equal(getattr(before.frame, t), getattr(sketch.frame, t))
        for t in ("origin", "u", "v", "normal")
    )


def rehinged(like: PlacedPose, before: Leaf | None, after: Leaf | None) -> PlacedPose | None:
    """The fitted bend `like` with its hinge moved as a midrib edit from the flat blade
    `before` to `after` moves it: the fit's hinge plus the change in the hinge read from each
    blade's midrib in `like`'s frame (margin_relief). Read afresh instead, the fit's hinge was
    lost: a 1% move of one midrib point moved ovate folded 60 and rolled 0.4 0.0164 of its
    length, sagittate folded 45 and curled 0.5 9.2e-3, the same read from the midrib unmoved;
    now 6.6e-4 and 1.8e-4 (test_unfold_in_app). None when either midrib reads no hinge."""
    fit = like.pose.relief
    if before is None or after is None or fit is None:
        return None

    def hinge(leaf: Leaf) -> Any:
        blade = [np.column_stack(like.frame.to_plane(c)) for c in (leaf.boundary, *leaf.veins)]
        return margin_relief(blade[0], blade[1:])

    old, new = hinge(before), hinge(after)
    if old is None or new is None:
        return None
    x = np.asarray(fit.along)
    moved = np.asarray(fit.midrib) + new.hinge_height(x) - old.hinge_height(x)
    relief = replace(fit, midrib=tuple(float(z) for z in moved))
    return PlacedPose(replace(like.pose, relief=relief), like.frame)


def keeps_refusal(state: State) -> bool:
    """Whether the document `state`'s leaf is run as given, no pose fitted to it
    (core/unfolded.as_given): its leaf opened in 3D was refused one (State.unposed), and as
    edited since (a sketch edit, a slider back at flat) it has no bend and lies no more than
    REFIT times as far off its plane. Its Pipeline fitted each edit's curves again, new bytes
    for unfolded.py's memo: 1.8-2.7 s of CPU an edit of a cup (review37b)."""
    leaf, refused = state.leaf, state.unposed
    if leaf is None or leaf.bend is not None or refused is None:
        return False
    return plane_share(leaf) <= REFIT * refused


class Bending:
    """The Session's bend edits (mixed into session.Session, which has the state and history)."""

    state: State
    _bend_base: State | None = None
    derived: Any  # the Session's: a loaded leaf's sketch, derived from its first result
    _derived_leaf: Leaf | None  # the leaf it draws

    @property
    def pose(self) -> Pose:
        """The document's pose (flat when it has none)."""
        return pose_of(self.state.leaf)

    @property
    def half_width(self) -> float:
        """The document's blade's half width per its length, on its sketch's plane when it has
        one (`blade_half_width`): the sliders' roll is in shares of a half turn over it."""
        sketch = self.state.sketch
        return blade_half_width(self.state.leaf, None if sketch is None else sketch.frame)

    def sketch_leaf(self, sketch: Any, before: Any = None) -> Leaf | None:
        """The leaf a sketch draws, edited from the Sketch `before` (the editor's; else the one
        the document's leaf is drawn by, `drawn_sketch`), bent by the document's pose (Session's
        sketch edits): a fitted leaf's in its own frame and relief, its hinge moved with its
        midrib (`keeps_fit`, `rehinged`). Either way the sliders' figures stay: a fitted bend's
        curl, roll and twist are per unit, and kept whole, an apex dragged 15% out took ovate
        folded 45 and curled 0.4996 to a curl of 0.5745 (test_unfold_in_app)."""
        flat = sketch.to_leaf()
        leaf = self.state.leaf
        like = None if leaf is None else leaf.bend
        before = self.drawn_sketch() if before is None else before
        if flat is not None and keeps_fit(like, before, sketch):
            same = np.array_equal(before.veins[0], sketch.veins[0])
            kept = like if same else rehinged(like, before.to_leaf(), flat)
            if kept is not None:
                return posed(flat, self.pose, kept)
        return posed(flat, self.pose, like, sketch.frame)

    def drawn_sketch(self) -> Any:
        """The Sketch the document's leaf is drawn by: its own, else the one derived from its
        result (editable_sketch), also while a slider's run is pending: the derived sketch
        draws a leaf the sliders re-posed (`set_bend`). Without it, an edit made in that window
        found the fit's frame again, and moved ovate folded 60 and rolled 0.4 0.016 of its
        length (test_unfold_in_app)."""
        sketch = self.editable_sketch()
        if sketch is None and self.state.sketch is None and self._derived_leaf is self.state.leaf:
            return self.derived
        return sketch

    def set_bend(self, pose: Pose, final: bool = True) -> None:
        """A new pose: `final=False` while a slider is held (shown, not an undo step), `True` on
        release: one undo step from before the drag. Nothing without a leaf, or for a leaf
        the sliders may not bend (`can_pose`).

        Raises
        ------
        LeafError
            For a pose past what it keeps of this blade (core/pose_limits.py), naming the term,
            its value and its range; the document is left as it was (a drag's steps before it
            made one undo step on release)."""
        leaf = self.state.leaf
        if not can_pose(leaf):
            return
        bent = None
        if leaf is not None and not _same_pose(pose, self.pose):
            sketch = self.state.sketch
            # a fitted bend kept by sketch edits (`keeps_fit`) is re-posed in its own frame and
            # relief: read again on the sketch's plane, ovate folded 60 and rolled 0.4 moved
            # 0.016 of its length for a nudge of 1e-6° after a sketch edit
            plane = sketch.frame if sketch is not None and not fitted(leaf.bend) else None
            # a pose past what it keeps of this blade is refused (a LeafError) and the
            # document stays as it was: set_bend(Pose(fold=89)) was taken and kept 0.83 of
            # the blade's area
            try:
                bent = posed(flat_leaf(leaf), pose, leaf.bend, plane, check=True)
            except LeafError as exc:
                if final:
                    self._end_bend()
                if isinstance(exc, PoseRefused):  # said in the sliders' terms
                    raise LeafError(refusal(exc, pose, self.half_width)) from None
                raise
        if self._bend_base is None:
            self._bend_base = self.state
        if bent is not None:
            if self.state.sketch is None and self._derived_leaf is leaf:
                self._derived_leaf = bent  # the derived sketch still draws this blade
            self._apply(replace(self.state, leaf=bent), "edit", live=not final)
        if final:
            self._end_bend()

    def _end_bend(self) -> None:
        """A drag's end: its bends since the drag began one undo step, if any."""
        base, self._bend_base = self._bend_base, None
        if base is not None and base.leaf is not self.state.leaf:
            text = bend_text(self.pose, self.half_width)
            self.history.push(Step(text, base, self.state))
