"""Bent leaves: the paper's steps run on the flat blade, and a smooth bend carries the mesh into
3D (issue 21, build item 1).

A leaf given with a bend (`Leaf.bend`) has its points in 3D, bent. The pipeline flattens them
(`Bend.flatten`), runs every step of the paper on the flat blade, where the boundary's PCA plane
is the blade's own plane, and carries the result back (`bent_result`): the mesh, the GMM
samples and the leaf the metrics are measured against. A leaf without a bend is the case of no
bend and runs exactly as before.

`Pose` is the bend a form knows (forms/make.py): in the blade's coordinates (the base at the
origin, the midrib along +x, the relief on +z), a roll bends each cross-section into a circular
arc of curvature `roll` (as a grass blade or a young leaf rolls), a fold turns each half up about
the midrib by `fold` degrees, a twist turns each cross-section about the midrib by twist · x
radians (a helicoid: a twisted grass blade or a propeller), and a curl lays the midrib on a
circle of curvature 2 · curl (z = curl · x² at the base), in that order. All are undone exactly,
and the blade is what the form drew before posing: a fold of 75° or a rolled grass blade is
reconstructed as well as the flat leaf, where the boundary's PCA plane saw it side-on and the
mesh broke (issue 21, finding 1).

A pose bends about the blade's own relief (`Pose.relief`, pose_relief.py, read from the flat
blade's curves by a form, the app's bend sliders and a project): the fold turns each half rigidly
about the midrib as it stands (hinge_fold.py), the roll bends each cross-section about its mean
height and the curl the blade about its midrib's mean height as the roll and fold leave it, so a
domed blade keeps its size (bench_bent.py --size, an ovate form's area posed over flat; about the
margin's plane, the relief lifted straight up by the fold and carried toward the roll's and curl's
axes, before: fold 30° 0.999 (0.90), 60° 0.993 (0.82), 75° 0.990 (0.79), roll 0.5 0.998 (0.86);
curled 1, its midrib 0.997 as long (0.92) and its area 1.017 (0.94)). A fold and a curl together
bend a channel along its length: its halves shorten (folded 75° and curled 1, 0.66 of the area,
against 0.48). A pose without a relief (a project saved before it, a pose fitted to curves in 3D
too large for a relief, core/unfold.py) bends the sheet z = 0 as before: the fold y -> y cos(fold),
z += |y| sin(fold) (fold and curl were once shears, z += |y| tan(fold) + curl · x²: an ovate form
folded 60° had 1.78 times its flat area).

The roll (and the curl, along the midrib) carries a relief h (a margin's wave, raised veins)
along the rolled normal: the cross-section's point (v, h) goes to the angle v / R about the axis
(R = 1 / roll) at radius R - h outward, R exp(-h / R) inward (the same slope where h = 0). A
relief as high as the radius, which R - h took through the axis (a wave of 0.1 on a tube: 15 of
the pose grid's 101 poses were refused), is drawn in toward it and never through, so every
relief is undone exactly.

The heights and `Result.height` stay those of the flat blade's surface (its relief); the mesh's
points are bent (bent_mesh.py), and its curvature arrays are the bent surface's
(bent_curvature.py: `carry_jet` takes a point's derivatives through the pose in closed form).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from leafstudio.core.bent_curvature import Jet
from leafstudio.core.buckets import kernel_array
from leafstudio.core.carried import carried_vectors
from leafstudio.core.hinge_fold import BAND, HingeFold, fold_share
from leafstudio.core.pose_jet import HINGE, PLAIN, posed_jet
from leafstudio.core.pose_relief import Relief
from leafstudio.core.prepare.units import Units
from leafstudio.model import Leaf

ROLL_SAG = 1.25e-3  # of a roll's radius: a bent chord stands no farther off (sag_splits); what
# cuts every 0.1 radians of roll kept it to, r (1 − cos 0.05), and 8.7 of a bent run's 61 ms
SAG = 1e-4  # bent_mesh.sag_splits: a bent edge's midpoint may stand this share of the mesh's
# extent off its chord
ROUND_OFF = 1e-12  # of the points' largest coordinate: a height or a y within it is 0 (carry_jet)
SEAM = 0.1  # flat_curve: points this share of a half turn from a tube's seam may lie either side
FLAT = (np.array([0.0, 1.0]), np.zeros((4, 1)))  # the sheet z = 0 as a spline's pieces (pose_jet)


@dataclass(frozen=True)
class Pose:
    """A form's fold (degrees, each half turned up about the midrib), curl (the midrib laid on
    a circle of curvature 2 · curl: z = curl · x² at the base; positive curls the apex up) and
    roll (the cross-section's curvature, 1 / its radius; positive rolls the margins up), in the
    blade's coordinates (module docstring)."""

    fold: float = 0.0
    curl: float = 0.0
    roll: float = 0.0
    twist: float = 0.0  # radians the cross-section turns about the midrib per unit of length
    # the flat blade's relief, which the fold turns about and the roll and curl bend without
    # stretching (pose_relief.py); None: the sheet z = 0 (an older project, a pose fitted to
    # curves too large for one: core/unfold.py). Not compared: the sliders' pose is the same
    # pose on any blade
    relief: Relief | None = field(default=None, compare=False)

    def apply(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) flat blade points, bent: rolled, folded, twisted about the midrib, then
        curled."""
        points = np.array(points, dtype=float)
        sheet = None  # the roll's, at x, which the roll and the fold keep: the fold's hinge
        if self.roll != 0:  # the axis: y = 0, z = the sheet + 1 / roll
            sheet = self._sheet_height(points[:, 0])
            points[:, 1], rolled = _wrapped(points[:, 1], points[:, 2] - sheet, self.roll)
            points[:, 2] = rolled + sheet
        if self.fold != 0:
            points[:, 1], points[:, 2] = self._folded(points, sheet)
        if self.twist != 0:
            points[:, 1:] = _turned(points, self.twist)
        if self.curl != 0:  # the axis: x = 0, z = the level + 1 / (2 curl)
            level = self._level()
            points[:, 0], curled = _wrapped(points[:, 0], points[:, 2] - level, 2 * self.curl)
            points[:, 2] = curled + level
        return points

    def carry(self, points: np.ndarray, units: Units | None = None) -> np.ndarray:
        """`apply` in one compiled kernel (pose_jet.py), to its round-off: a bent run's mesh is
        carried so (bent_result.py; apply took 3.5 ms for the 29,000 points a four-term pose's
        grid-128 run carries, this 1.7). A form's curves stay bent by `apply` (numpy's exp is
        not the kernel's: the flat run of a blade an ulp off can make another mesh). `units`:
        the points at its unit size, carried in the world and returned at it (Units.to_world
        and to_unit in the kernel, the same sums)."""
        return self._posed(kernel_array(points), np.zeros((0, 5, 3)), units)[0]

    def carry_jet(self, jet: Jet, units: Units | None = None) -> Jet:
        """A jet of flat blade points (bent_curvature.py) bent as `apply` bends the points, in
        closed form (pose_jet.py); on a fold's crease (y = 0) from its + side, on a roll's or
        curl's sheet (height 0) from the relief's. `units` as `carry` takes it: the derivatives
        times its scale, then over it."""
        return self._posed(kernel_array(jet[0]), kernel_array(jet[1]), units)

    def _posed(self, points: np.ndarray, d: np.ndarray, units: Units | None = None) -> Jet:
        """`pose_jet.posed_jet` of (n, 3) points and their (n, 5, 3) derivatives, or (0, 5, 3)
        for the points alone (at `units`' unit size)."""
        sheet = midrib = FLAT
        if self.relief is not None:
            sheet, midrib = self.relief.pieces("mean"), self.relief.pieces("midrib")
        fold, c, s, tan, share, band = 0, 1.0, 0.0, 0.0, 0.0, 1.0
        if self.fold != 0 and self.relief is None:
            angle = np.deg2rad(self.fold)
            fold, c, s, tan = PLAIN, np.cos(angle), np.sin(angle), np.tan(angle)
        elif self.fold != 0:
            turn = self._hinge_fold()
            fold, c, s, share, band = HINGE, turn.c, turn.s, turn.share, turn.band
        level = self._level() if self.curl != 0 else 0.0
        return posed_jet(
            points, d, float(self.roll), *sheet, fold, float(c), float(s), float(tan),
            float(share), float(band), *midrib, float(self.twist), float(self.curl), level,
            ROUND_OFF, *((np.zeros(3), 1.0) if units is None else (units.offset, units.scale)),
        )  # fmt: skip

    def flatten(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) bent points back on the flat blade (the inverse of `apply`, for less than half
        a turn of roll each side)."""
        points = np.array(points, dtype=float)
        if self.curl != 0:
            level = self._level()
            points[:, 0], flat = _unwrapped(points[:, 0], points[:, 2] - level, 2 * self.curl)
            points[:, 2] = flat + level
        if self.twist != 0:  # x is kept by the twist and the fold
            points[:, 1:] = _turned(points, -self.twist)
        sheet = None if self.roll == 0 else self._sheet_height(points[:, 0])  # x is kept
        if self.fold != 0:
            points[:, 1], points[:, 2] = self._unfolded(points, sheet)
        if self.roll != 0:
            points[:, 1], flat = _unwrapped(points[:, 1], points[:, 2] - sheet, self.roll)
            points[:, 2] = flat + sheet
        return points

    def _level(self) -> float:
        """The height the curl bends the blade about: its midrib's mean as the roll, fold and
        twist leave it (Relief.posed_level), or the sheet's 0."""
        if self.relief is None:
            return 0.0
        return self.relief.posed_level(replace(self, curl=0.0))

    def _sheet_height(self, x: np.ndarray) -> np.ndarray:
        """The height the roll bends each cross-section about: its relief's mean, or 0."""
        return np.zeros(len(x)) if self.relief is None else self.relief.sheet_height(x)

    def _hinge_height(self, x: np.ndarray, sheet: np.ndarray | None) -> np.ndarray:
        """The midrib's height once rolled (the fold turns each half about it): the roll carries
        the midrib's height h over the sheet s to s + g(h − s) (`_rolled_rise`; pose_jet._rolled
        for a jet); the roll's `sheet` height at x given (None: found)."""
        midrib = self.relief.hinge_height(x)
        if self.roll == 0:
            return midrib
        sheet = self.relief.sheet_height(x) if sheet is None else sheet
        return sheet + _rolled_rise(midrib - sheet, self.roll)[0]

    def _hinge_fold(self) -> HingeFold:
        """The fold about the hinge (hinge_fold.py), the relief's turn eased as it leaves
        room."""
        fold = np.deg2rad(self.fold)
        share = fold_share(self.fold, self.relief.fold_room(self.fold, self.roll))
        length = self.relief.knots[-1] - self.relief.knots[0]
        return HingeFold(np.cos(fold), np.sin(fold), share, BAND * length)

    def _folded(
        self, points: np.ndarray, sheet: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """y and z of (n, 3) points folded: each half turned up by the fold about the midrib,
        about its hinge with a relief (hinge_fold.py); else y -> y cos, z += |y| sin, the
        relief lifted straight up. `sheet`: the roll's height at x (`_hinge_height`)."""
        fold = np.deg2rad(self.fold)
        y, z = points[:, 1], points[:, 2]
        if self.relief is None:  # z from the turned y, as `flatten` takes it back: 0 exact
            return y * np.cos(fold), z + np.abs(y * np.cos(fold)) * np.tan(fold)
        hinge = self._hinge_height(points[:, 0], sheet)
        y, off = self._hinge_fold().folded(y, z - hinge)
        return y, off + hinge

    def _unfolded(
        self, points: np.ndarray, sheet: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """The inverse of `_folded`."""
        fold = np.deg2rad(self.fold)
        y, z = points[:, 1], points[:, 2]
        if self.relief is None:
            return y / np.cos(fold), z - np.abs(y) * np.tan(fold)
        hinge = self._hinge_height(points[:, 0], sheet)
        y, off = self._hinge_fold().unfolded(y, z - hinge)
        return y, off + hinge

    def flat_curve(self, points: np.ndarray, ring: bool = False) -> np.ndarray:
        """`flatten` for a curve's (n, 3) points in order along it (`ring`: closed): a rolled
        tube's points near its seam kept on their side (`unseamed`)."""
        return self.unseam(self.flatten(points), ring)

    def unseam(self, flat: np.ndarray, ring: bool = False) -> np.ndarray:
        """A curve's (n, 3) flattened points with those near a rolled tube's seam on their side
        (`unseamed`)."""
        flat = np.array(flat, dtype=float)
        flat[:, 1] = unseamed(flat[:, 1], self.roll, ring)
        return flat

    def trim(self, points: np.ndarray) -> None:
        """A pose cuts nothing out of the blade (model.Bend.trim)."""
        return None

    def on_midrib(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) flat blade points moved along z to the midrib's height at their x: the hinge
        the fold turns each half about, which it leaves in place (an export's axes are found
        there, assets/placement.py); as given without a relief (the sheet z = 0's fold moves
        nothing at y = 0)."""
        points = np.array(points, dtype=float)
        if self.relief is not None:
            points[:, 2] = self.relief.hinge_height(points[:, 0])
        return points

    def off_hinge(self, points: np.ndarray) -> np.ndarray:
        """(n,) heights of flat blade points over the hinge the pose bends about: the midrib's
        height (`on_midrib`), the sheet z = 0 without a relief. A form's midrib is on it; a
        pose fitted about the margin's plane can bend a midrib standing off it, its heights
        making up for a term (assets/placement.carried: ovate folded 75 and rolled 1, fitted a
        curl of 0.36, 0.036 of the length)."""
        points = np.asarray(points, dtype=float)
        if self.relief is None:
            return points[:, 2].copy()
        return points[:, 2] - self.relief.hinge_height(points[:, 0])

    def key(self) -> bytes:
        """Bytes that change with the bend (Leaf.fingerprint); no roll or twist keeps today's."""
        terms = [self.fold, self.curl] + ([self.roll] if self.roll != 0 else [])
        terms += [np.inf, self.twist] if self.twist != 0 else []  # inf: no roll's key alike
        return np.array(terms).tobytes() + (b"" if self.relief is None else self.relief.key())

    def entry(self) -> dict[str, float]:
        """The project's "bend" entry (sources/files.py): "roll" and "twist" only when there
        are."""
        entry = {"fold": self.fold, "curl": self.curl}
        entry |= {"roll": self.roll} if self.roll != 0 else {}
        entry |= {"twist": self.twist} if self.twist != 0 else {}
        return entry | ({"relief": self.relief.entry()} if self.relief is not None else {})

    def crease(self, points: np.ndarray) -> np.ndarray | None:
        """(n,) signed distances of flat points from the line the bend creases along (the
        midrib, y = 0, for a fold), or None when it has none: the mesh is cut there first."""
        return np.asarray(points, dtype=float)[:, 1] if self.fold != 0 else None

    def crease_side(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """At (n, 3) flat points: their bent points' signed distances from the plane the fold
        parts the halves by (y = 0 once rolled and folded: the twist turns it and the curl
        bends it with the halves, keeping distances from it), and (n, 3) the unit vector
        across it there; None without a fold. A solid's offsets keep off it (solid.py)."""
        if self.fold == 0:
            return None
        points = np.asarray(points, dtype=float)
        folded = replace(self, twist=0.0, curl=0.0).apply(points)
        rest = replace(self, fold=0.0, roll=0.0)
        across = carried_vectors(rest, folded, np.broadcast_to([0.0, 1.0, 0.0], points.shape))
        return folded[:, 1], across / np.linalg.norm(across, axis=1, keepdims=True)

    def sag_tolerance(self, extent: float) -> float:
        """How far a bent chord of a mesh `extent` across may stand off the bent surface
        (sag_splits): SAG of the extent, and ROLL_SAG of a roll's radius (a grass blade's tube,
        a hundredth of its length across)."""
        return min(SAG * extent, ROLL_SAG / abs(self.roll)) if self.roll else SAG * extent


def _rolled_rise(u: np.ndarray, k: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How far a height u over a roll's sheet stands over it once rolled at the midrib (y = 0),
    with its first and second derivatives: g(u) = R (1 − ρ(u / R)), ρ `_rolled_radius`
    (R = 1 / k): u itself below the sheet, drawn in above it."""
    t = u * k
    inward = np.exp(-np.maximum(t, 0))
    g = np.where(t <= 0, u, (1 - inward) / k)
    return g, np.where(t <= 0, 1.0, inward), np.where(t <= 0, 0.0, -k * inward)


def _rolled_radius(u: np.ndarray) -> np.ndarray:
    """The rolled radius over the roll's, for heights u in radii toward the axis: 1 - u outward
    (u <= 0, along the rolled normal as on the flat blade), exp(-u) inward (the same slope at 0,
    and never through the axis)."""
    return np.where(u <= 0, 1 - u, np.exp(-np.maximum(u, 0)))


def _unrolled_height(k: np.ndarray) -> np.ndarray:
    """The inverse of `_rolled_radius`: heights in radii toward the axis, for radii k over the
    roll's."""
    return np.where(k >= 1, 1 - k, -np.log(np.minimum(k, 1)))


def _wrapped(u: np.ndarray, h: np.ndarray, k: float) -> tuple[np.ndarray, np.ndarray]:
    """A sheet's coordinate u and height h with the sheet wrapped on a circle of curvature k
    (the axis at height 1 / k; u its arclength, h along its normal): the roll across the midrib
    and the curl along it. Half a turn at most each way (a tube's margins at exactly ±π stay on
    their side); a height toward the axis is drawn in (`_rolled_radius`), never through it."""
    r = 1.0 / k
    angle = np.clip(u * k, -np.pi, np.pi)
    radius = r * _rolled_radius(h * k)
    return np.sin(angle) * radius, r - np.cos(angle) * radius


def _unwrapped(u: np.ndarray, h: np.ndarray, k: float) -> tuple[np.ndarray, np.ndarray]:
    """The inverse of `_wrapped`, for less than half a turn each way."""
    r = 1.0 / k
    sign = np.sign(r)
    across, toward = sign * u, sign * (r - h)
    return np.arctan2(across, toward) * r, r * _unrolled_height(np.hypot(across, toward) * abs(k))


def _turned(points: np.ndarray, twist: float) -> np.ndarray:
    """(n, 2) y and z of (n, 3) points turned about the x axis by twist · x radians."""
    angle = twist * points[:, 0]
    c, s = np.cos(angle), np.sin(angle)
    y, z = points[:, 1], points[:, 2]
    return np.column_stack([c * y - s * z, s * y + c * z])


def flat_leaf(leaf: Leaf) -> Leaf:
    """The leaf on its flat blade: `leaf` itself when it has no bend."""
    if leaf.bend is None:
        return leaf
    curves = flat_curves(leaf.bend, [leaf.boundary, *leaf.veins], [True])
    return Leaf(boundary=curves[0], veins=curves[1:])


def flat_curves(bend, curves: list[np.ndarray], rings: list[bool]) -> list[np.ndarray]:
    """`flat_curve` of each of the (n_i, 3) `curves` (`rings[i]`: closed; False past the
    list), their points flattened in one call: a fold about its hinge pays its per-call cost
    once (a folded form's 27 curves, one at a time, took 10 ms of a 60 ms run)."""
    own = getattr(bend, "flat_curve", None)  # Pose, PlacedPose
    if own is None or not curves:
        return [bend.flatten(c) for c in curves]
    points = np.vstack([np.asarray(c, dtype=float).reshape(-1, 3) for c in curves])
    flat = np.split(bend.flatten(points), np.cumsum([len(c) for c in curves])[:-1])
    seam = getattr(bend, "unseam", None)
    if seam is None:
        return flat
    return [seam(f, i < len(rings) and rings[i]) for i, f in enumerate(flat)]


def flat_curve(bend, points: np.ndarray, ring: bool = False) -> np.ndarray:
    """(n, 3) flat points of a curve's (n, 3) bent points, in order along it (`ring`: closed):
    a pose's own `flat_curve` (a tube's seam, `unseamed`), else the bend's `flatten`."""
    own = getattr(bend, "flat_curve", None)  # Pose, PlacedPose
    return bend.flatten(points) if own is None else own(points, ring)


def unseamed(v: np.ndarray, roll: float, ring: bool = False) -> np.ndarray:
    """(n,) flat v (across the midrib) of a curve's points, in order along it, with the points
    near a tube's seam on their side.

    A tube's margins meet where the roll reaches half a turn, and a point there flattens onto
    either margin: one a hair past the seam (a pose fitted to the curves, core/unfold.py) went to
    the other one and the outline crossed itself (a grass blade rolled into a tube). A point
    within SEAM of the seam keeps the side of the last point before it that is clear of it."""
    if roll == 0 or len(v) < 2:
        return v
    half = np.pi / abs(roll)  # the seam's v
    clear = np.abs(v) < (1 - SEAM) * half
    if clear.all() or not clear.any():
        return v
    order = np.arange(len(v))
    if ring:  # from a clear point: each run along the seam has one before it
        order = np.roll(order, -int(np.argmax(clear)))
    last = np.where(clear[order], np.arange(len(order)), -1)
    last = np.maximum.accumulate(last)
    last[last < 0] = int(np.argmax(clear[order]))  # an open curve's first run: the next clear
    side = np.sign(v[order[last]])
    along = v[order]
    wrong = ~clear[order] & (np.sign(along) != side) & (side != 0)
    along[wrong] += side[wrong] * 2 * half
    out = np.array(v, dtype=float)
    out[order] = along
    return out


def sheared_flatten(pose: Pose, points: np.ndarray) -> np.ndarray:
    """(n, 3) blade points bent by `pose` as version 1 of the project format bent them (a fold
    and a curl were shears: z += |y| tan(fold) after the roll, then the twist, then
    z += curl · x²), back on the flat blade: projects saved then are bent again (sources/
    bend_entry.py)."""
    points = np.array(points, dtype=float)
    points[:, 2] -= pose.curl * points[:, 0] ** 2
    if pose.twist != 0:
        points[:, 1:] = _turned(points, -pose.twist)
    points[:, 2] -= np.abs(points[:, 1]) * np.tan(np.deg2rad(pose.fold))
    if pose.roll != 0:
        points[:, 1], points[:, 2] = _unwrapped(points[:, 1], points[:, 2], pose.roll)
    return points
