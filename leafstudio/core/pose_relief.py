"""A pose's relief: the heights a fold turns each half about and a roll and a curl bend without
stretching (issue 21: a designer's leaf "at its real size").

`bend.Pose` bends the blade's sheet, the plane z = 0 its margin lies on, and carries the relief
(a form's dome, a drawn leaf's raised veins) on it. A domed blade's relief all stands on one
side of that sheet, so it was drawn in wherever the blade bent: a fold lifted each half's relief
straight up instead of turning it with the half, and a roll or a curl offset it toward the axis,
each arc shortened by 1 − zκ. An ovate form kept 0.90 of its flat area folded 30°, 0.82 folded
60°, 0.86 rolled 0.5 and 0.94 curled 1 (`bench_bent.py --size`).

A pose that knows the blade's relief bends about it instead: the fold turns each half rigidly about
the midrib as it stands (its height over x, the hinge), the roll bends each cross-section about its
own mean height (the sheet), so the relief's first-order stretch averages out over each section,
and the curl lays the midrib on its circle by its length (`posed_level`). The profiles are read
from the flat blade's curves (`relief_of`): the hinge through the midrib's points, the sheet at
KNOTS places along the blade; both are cubic splines in x (C², linear past the ends): a fold's
hinge with a kink would crease the blade across at each knot. A pose fitted to curves in 3D
(core/unfold.py) has a relief of its own (`margin_relief`): the flat midrib's heights for the
hinge, the margin's plane for the sheet, and the margin's rise and fall off the hinge. A pose
without a relief (a project saved before it, a pose fitted to curves past unfold.HINGE_SIZES)
bends as it did."""

from __future__ import annotations

import hashlib
import threading
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import shapely
from scipy.interpolate import CubicSpline, LinearNDInterpolator, PPoly
from shapely.geometry import Polygon

from leafstudio._shared.blas import one_blas_thread
from leafstudio.core.prepare.polygon import unit_power

if TYPE_CHECKING:  # bend.py imports this module: the types only
    from leafstudio.core.bend import Pose
    from leafstudio.core.plane import Frame

KNOTS = 24  # places along the blade the sections' mean heights are read at
MARGIN_KNOTS = 8  # margin_relief's: its sheet is 0 at each
ROOM_SLACK = np.deg2rad(5.0)  # Relief.fold_room: kept clear of the midrib's plane
CREASE = 0.05  # of the half width: points nearer the midrib than this have no angle off it
LEVEL_SAMPLES = 64  # points along the midrib a pose's curl finds its level from (posed_level)
MIDRIB_POINTS = 128  # the most midrib points the hinge passes through (a project saves them)
SAMPLES = 2048  # grid points over the blade's bounding box the sections' means are taken over

Profile = tuple[np.ndarray, np.ndarray, np.ndarray]  # a height over x, its first and second x

RECENT = 8  # blades whose reliefs relief_of keeps
_RECENT: dict[bytes, Relief | None] = {}  # relief_of's last RECENT, oldest first
_RECENT_LOCK = threading.Lock()  # a form's blade is grown on a worker thread


@dataclass(frozen=True)
class Relief:
    """The flat blade's heights a pose bends about, in the blade's coordinates (the midrib along
    +x, the relief on +z)."""

    along: tuple[float, ...]  # x of the midrib's points, increasing
    midrib: tuple[float, ...]  # their heights: a fold's hinge passes through them
    knots: tuple[float, ...]  # x, increasing, evenly over the blade
    mean: tuple[float, ...]  # each cross-section's mean height there: a roll's sheet
    half_width: float  # the blade's widest reach across the midrib (how far a roll turns it)
    rise: float = 0.0  # radians: the steepest the relief rises from the hinge across (its
    fall: float = 0.0  # points' angle atan2(±(z − hinge), |y|)), and falls (`fold_room`)
    # the profiles linear past their ends (`profile_spline`); False: a project's relief saved
    # before, whose curves were bent with the end pieces' cubics carried on, flattened so
    linear_ends: bool = True
    # a pose fitted to curves in 3D (core/unfold.py): its sheet the margin's plane
    # (`margin_relief`), or for a roll alone, its sections' means read off the curves as it
    # laid them flat (`sheet_relief`); said, not read off the means, which a drawn blade with a
    # flat midrib has all 0 too
    on_margin: bool = False
    _cache: dict = field(default_factory=dict, init=False, compare=False, repr=False)  # splines

    def _spline(self, name: str) -> PPoly:
        if name not in self._cache:  # made once: a pose bends the mesh's points, then its jets
            x = self.along if name == "midrib" else self.knots
            self._cache[name] = profile_spline(x, getattr(self, name), self.linear_ends)
        return self._cache[name]

    def _profile(self, name: str, x: np.ndarray) -> Profile:
        spline = self._spline(name)
        return spline(x), spline(x, 1), spline(x, 2)

    def pieces(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """The "midrib" or "mean" profile's spline as its breaks and (4, m) coefficients
        (pose_jet.py's kernel evaluates it)."""
        spline = self._spline(name)
        return np.ascontiguousarray(spline.x), np.ascontiguousarray(spline.c)

    def scaled(self, factor: float) -> Relief:
        """The same relief on a blade `factor` times as large (its angles and ends kept)."""
        along, midrib, knots, mean = (
            tuple(float(v) * factor for v in values)
            for values in (self.along, self.midrib, self.knots, self.mean)
        )
        half_width = self.half_width * factor  # a fresh cache: its splines are in the old units
        return replace(
            self, along=along, midrib=midrib, knots=knots, mean=mean, half_width=half_width
        )

    def sloped(self, rise: float, fall: float) -> Relief:
        """The same relief with the rise and the fall given, its profiles' splines kept (they
        are of its profiles alone): core/unfold.py's fits set them afresh each round, and a
        fresh cache made each spline again (ovate serrate waved 0.1, read from a CSV: 4054
        splines made in one open, 1722 distinct; /work/notes/open36)."""
        relief = replace(self, rise=rise, fall=fall)
        relief._cache.update({k: v for k, v in self._cache.items() if k in ("midrib", "mean")})
        return relief

    def mirrored(self) -> Relief:
        """The same relief seen from the blade's other side (its frame turned half about the
        midrib, y and z negated): the heights negated, the rise and the fall swapped."""
        midrib, mean = (tuple(0.0 - v for v in values) for values in (self.midrib, self.mean))
        return replace(self, midrib=midrib, mean=mean, rise=self.fall, fall=self.rise)

    def hinge(self, x: np.ndarray) -> Profile:
        """The midrib's height at (n,) x, with its first and second derivatives."""
        return self._profile("midrib", x)

    def sheet(self, x: np.ndarray) -> Profile:
        """The cross-section's mean height at (n,) x, with its first and second derivatives."""
        return self._profile("mean", x)

    def hinge_height(self, x: np.ndarray) -> np.ndarray:
        """The midrib's height at (n,) x alone (a pose's points need no derivatives)."""
        return self._spline("midrib")(x)

    def sheet_height(self, x: np.ndarray) -> np.ndarray:
        """The cross-section's mean height at (n,) x alone."""
        return self._spline("mean")(x)

    def key(self) -> bytes:
        """Bytes that change with the relief (Pose.key)."""
        numbers = [*self.along, *self.midrib, *self.knots, *self.mean]
        numbers += [self.half_width, self.rise, self.fall]
        return np.array(numbers).tobytes() + (b"" if self.linear_ends else b"cubic ends")

    def entry(self) -> dict[str, Any]:
        """The project's "relief" entry of a "bend" (sources/bend_entry.py)."""
        return {
            "along": list(self.along),
            "knots": list(self.knots),
            "midrib": list(self.midrib),
            "mean": list(self.mean),
            "half_width": self.half_width,
            "rise": self.rise,
            "fall": self.fall,
            "sheet": "margin" if self.on_margin else "mean",  # what a roll bends about
        } | ({"ends": "linear"} if self.linear_ends else {})

    @classmethod
    def from_entry(cls, value: Any) -> Relief:
        """A Relief from its `entry`; ValueError unless it reads whole (increasing x, as many
        heights, all finite)."""
        along, midrib, knots, mean = (
            _numbers(value[k]) for k in ("along", "midrib", "knots", "mean")
        )
        scalars = [float(value[k]) for k in ("half_width", "rise", "fall")]
        if not (_profile_reads(along, midrib) and _profile_reads(knots, mean)):
            raise ValueError("a relief's x and heights do not read whole")
        if not (np.isfinite(scalars).all() and min(scalars) >= 0):
            raise ValueError("a relief's half width, rise and fall must be numbers of 0 or more")
        if "sheet" in value:
            if value["sheet"] not in ("margin", "mean"):
                raise ValueError('a relief\'s "sheet" must be "margin" or "mean"')
            on_margin = value["sheet"] == "margin"
        else:  # saved before it said: margin_relief's knots, all its means 0 (relief_of's are
            # KNOTS, so a drawn blade with a flat midrib, its means 0 too, is not read as fitted)
            on_margin = len(knots) == MARGIN_KNOTS and not any(mean)
        ends = value.get("ends") == "linear"
        return cls(along, midrib, knots, mean, *scalars, linear_ends=ends, on_margin=on_margin)

    def posed_level(self, pose: Any) -> float:
        """The midrib's mean height as `pose` leaves it before its curl (a `bend.Pose` without
        its curl): what the curl bends the blade about, so the midrib keeps its length. About
        the blade's mean height, the area was kept but a folded blade's midrib, far under its
        raised halves, was stretched (ovate folded 75° and curled 1: 1.25 times as long); about
        the margin's plane, the midrib shrank (0.92) and the halves with it (0.48 of the area).
        A blade folded and curled is a channel bent along its length: its halves shorten
        (bench_bent.py --size)."""
        key = ("level", pose.fold, pose.roll, pose.twist)
        if key not in self._cache:  # once a pose: every call of its apply asks
            x = np.linspace(self.along[0], self.along[-1], LEVEL_SAMPLES)
            midrib = np.column_stack([x, np.zeros_like(x), self.hinge_height(x)])
            self._cache[key] = float(pose.apply(midrib)[:, 2].mean())
        return self._cache[key]

    def fold_room(self, fold: float, roll: float) -> float:
        """Radians a half may turn about the hinge before a point of it crosses the midrib's
        plane: a right angle less the relief's steepest rise or fall the fold's way (a dome
        folded down, a wavy margin folded up), half the roll's turn at the widest when it
        lifts the margins the fold's way, and ROOM_SLACK."""
        relief = self.rise if fold > 0 else self.fall
        chord = 0.5 * min(abs(roll) * self.half_width, np.pi) if roll * fold > 0 else 0.0
        return np.pi / 2 - relief - chord - ROOM_SLACK


def profile_spline(x: Any, z: Any, linear_ends: bool = True) -> PPoly:
    """The natural cubic spline through heights `z` at increasing `x`, linear past its ends
    (its second derivative is 0 there: C² still), as pieces one span long each side (the
    kernel's spline, pose_jet._spline, takes its end pieces past them). CubicSpline carried
    its end pieces' cubics on: a sagittate form's hinge fell to 0.28 of the length under its
    lobes' tips, behind the base where no midrib runs, and folded 60° it kept 0.92 of its area
    (the fold's turn eased for the steep rise that made). `linear_ends` False: that spline, for
    a relief saved before (Relief.linear_ends)."""
    x, z = np.asarray(x, dtype=float), np.asarray(z, dtype=float)
    spline = CubicSpline(x, z, bc_type="natural")
    if not linear_ends:
        return spline
    span = x[-1] - x[0]
    slopes = spline(x[[0, -1]], 1)
    left = [0.0, 0.0, slopes[0], z[0] - slopes[0] * span]  # on [x0 - span, x0]
    right = [0.0, 0.0, slopes[1], z[-1]]
    pieces = np.column_stack([left, spline.c, right])
    return PPoly(pieces, np.concatenate([[x[0] - span], x, [x[-1] + span]]))


def _numbers(value: Any) -> tuple[float, ...]:
    """A list of numbers from a project; ValueError for anything else (a string's characters
    read as digits)."""
    if not isinstance(value, (list, tuple)):
        raise ValueError("a relief's profiles must be lists of numbers")
    return tuple(float(t) for t in value)


def _profile_reads(x: tuple[float, ...], z: tuple[float, ...]) -> bool:
    """Whether a profile's x and heights make a spline: two or more, as many, finite, x
    increasing."""
    numbers = np.array([*x, *z])
    return (
        len(x) >= 2
        and len(x) == len(z)
        and bool(np.isfinite(numbers).all())
        and bool(np.all(np.diff(x) > 0))
    )


def relief_of(boundary: np.ndarray, veins: list[np.ndarray]) -> Relief | None:
    """The relief of a flat blade whose (n, 3) `boundary` and (m_i, 3) `veins` (midrib first)
    are in the blade's coordinates; None for a blade with no extent along x or no area.

    The hinge passes through the midrib's points (`_midrib`; a blade without one turns about
    its sections' means). The sections' means are those of the heights
    interpolated linearly between all the curves' points (a Delaunay triangulation) at grid
    points inside the outline, in a band of x around each knot. The last RECENT blades' reliefs
    are kept: a drawn leaf's bend sliders ask for the same one at every step (4 ms an ovate
    form's)."""
    boundary = np.asarray(boundary, dtype=float)
    veins = [np.asarray(v, dtype=float) for v in veins]
    digest = hashlib.blake2b(digest_size=16)
    for curve in (boundary, *veins):
        digest.update(np.ascontiguousarray(curve).tobytes() + str(curve.shape).encode())
    key = digest.digest()
    with _RECENT_LOCK:
        if key in _RECENT:
            return _RECENT[key]
    with one_blas_thread():  # the triangulation's barycentric transforms, a tiny LAPACK call a
        # triangle: with a second OpenBLAS thread waiting for a busy core, 0.01-4.2 s of CPU for
        # an ovate form's blade (find_simplex's first call, two cores under load), 0.00-0.01
        relief = _relief_of(boundary, veins)
    with _RECENT_LOCK:
        _RECENT[key] = relief
        while len(_RECENT) > RECENT:
            _RECENT.pop(next(iter(_RECENT)))
    return relief


def laid_flat(
    pose: Pose, frame: Frame, curves: list[np.ndarray]
) -> tuple[list[np.ndarray], Relief | None]:
    """The (n_i, 3) world `curves` (the boundary first, then the veins, midrib first) as `pose`
    lays them flat in `frame`, and the relief relief_of reads off them: how a fit about a
    form's relief reads it again after each round (unfold_rolled.py, unfold_mixed.py)."""
    flat = [
        pose.flat_curve(np.column_stack(frame.to_plane(c)), ring=i == 0)
        for i, c in enumerate(curves)
    ]
    return flat, relief_of(flat[0], flat[1:])


def _relief_of(boundary: np.ndarray, veins: list[np.ndarray]) -> Relief | None:
    """`relief_of`, made."""
    x0, x1 = float(boundary[:, 0].min()), float(boundary[:, 0].max())
    if not x1 > x0 or len(boundary) < 3:
        return None
    knots = np.linspace(x0, x1, KNOTS)
    polygon = Polygon(boundary[:, :2])
    if not polygon.is_valid:
        polygon = polygon.buffer(0)
    y0, y1 = float(boundary[:, 1].min()), float(boundary[:, 1].max())
    if polygon.is_empty or not y1 > y0:
        return None
    across = max(int(np.sqrt(SAMPLES * (y1 - y0) / (x1 - x0))), 4)
    along = max(SAMPLES // across, 2 * KNOTS)
    gx, gy = np.meshgrid(np.linspace(x0, x1, along), np.linspace(y0, y1, across))
    inside = shapely.contains_xy(polygon, gx.ravel(), gy.ravel())
    points = np.vstack([boundary, *[np.asarray(v, dtype=float) for v in veins if len(v)]])
    xy = np.column_stack([gx.ravel()[inside], gy.ravel()[inside]])
    if len(xy) == 0:
        return None
    # triangulated at about unit size, by a power of two (exact): Qhull's Delaunay overflowed
    # past 1e77 (a leaf at 1e90 opened in the app, and its bend slider raised QhullError)
    unit = unit_power(points[:, :2])
    heights = LinearNDInterpolator(points[:, :2] * unit, points[:, 2])(xy * unit)
    held = np.isfinite(heights)
    xy, heights = xy[held], heights[held]
    if len(xy) == 0:
        return None
    bin_of = np.clip(np.rint((xy[:, 0] - x0) / (x1 - x0) * (KNOTS - 1)).astype(int), 0, KNOTS - 1)
    count = np.bincount(bin_of, minlength=KNOTS)
    sums = np.bincount(bin_of, weights=heights, minlength=KNOTS)
    filled = count > 0
    mean = np.interp(knots, knots[filled], sums[filled] / count[filled])
    midrib = _midrib(np.asarray(veins[0], dtype=float), boundary) if veins else None
    if midrib is None:  # no midrib to turn about: the sections' means
        midrib = knots, mean
    half_width = max(-y0, y1)
    hinge = profile_spline(*midrib)(points[:, 0])
    clear = np.abs(points[:, 1]) > CREASE * half_width
    rise, fall = _rise_fall(points[clear, 2] - hinge[clear], points[clear, 1])
    return Relief(
        tuple(midrib[0].tolist()),
        tuple(midrib[1].tolist()),
        tuple(knots.tolist()),
        tuple(mean.tolist()),
        half_width,
        rise,
        fall,
    )


def _rise_fall(above: np.ndarray, across: np.ndarray) -> tuple[float, float]:
    """The steepest rise and fall (radians, 0 or more) of points (n,) `above` the hinge at (n,)
    `across` from it: a relief's Relief.rise and .fall."""
    angle = np.arctan2(above, np.abs(across))
    return max(float(angle.max(initial=0.0)), 0.0), max(float(-angle.min(initial=0.0)), 0.0)


def slopes_off(relief: Relief, points: np.ndarray, clear: float) -> tuple[float, float]:
    """The rise and the fall (Relief.rise, .fall) off `relief`'s hinge of the flat (n, 3)
    `points` farther from the midrib than `clear` of the farthest, as `relief_of` reads a
    form's past CREASE (core/unfold_rolled.py reads them of curves a fit laid flat)."""
    across = np.abs(points[:, 1])
    wide = points[across > clear * across.max()]
    return _rise_fall(wide[:, 2] - relief.hinge_height(wide[:, 0]), wide[:, 1])


def margin_relief(
    boundary: np.ndarray, veins: list[np.ndarray], slopes: tuple[float, float] | None = None
) -> Relief | None:
    """A relief whose hinge passes through the flat midrib's points (the first of the (m_i, 3)
    `veins`) and whose sheet is the margin's plane (z = 0), the blade's x and half width, and
    the margin's rise and fall off the hinge (`margin_slopes`), read from the (n, 3) `boundary`
    as it lies flat, in the blade's coordinates as for `relief_of`: a pose fitted to
    curves in 3D (core/unfold.py) folds about it, and the app's sliders bend such a leaf about
    it again (`Relief.on_margin`). None without a midrib, or when it doubles back. `slopes`:
    the rise and fall to give it instead of the margin's (unfold_hinge.hinge_relief sets its
    own: reading them took 0.63 of a waved serrate blade's 4.5 s of fitting, cProfile)."""
    if not veins:
        return None
    midrib = np.asarray(veins[0], dtype=float)
    if len(midrib) < 2 or np.any(np.diff(midrib[:, 0]) < 0):
        return None
    x0, x1 = float(boundary[:, 0].min()), float(boundary[:, 0].max())
    along, heights = _thinned(*_increasing(midrib[:, 0], midrib[:, 2], 1e-6 * (x1 - x0)))
    if len(along) < 2:
        return None
    knots = np.linspace(x0, x1, MARGIN_KNOTS)
    half_width = float(np.abs(boundary[:, 1]).max())
    zeros = (0.0,) * MARGIN_KNOTS
    relief = Relief(tuple(along), tuple(heights), tuple(knots), zeros, half_width, on_margin=True)
    return relief.sloped(*(margin_slopes(relief, boundary) if slopes is None else slopes))


def sheet_relief(knots: tuple[float, ...], mean: tuple[float, ...]) -> Relief:
    """A relief whose sheet is the sections' mean heights `mean` at increasing `knots` (x), its
    hinge flat: all a roll alone asks (a pose fitted to curves in 3D, core/unfold.py, reads
    them off its curves laid flat, as `relief_of` reads a form's; `Relief.on_margin`: fitted)."""
    ends = (knots[0], knots[-1])
    return Relief(ends, (0.0, 0.0), tuple(knots), tuple(mean), 1.0, on_margin=True)


def margin_slopes(relief: Relief, boundary: np.ndarray) -> tuple[float, float]:
    """The rise and the fall (Relief.rise, .fall) of the flat (n, 3) `boundary` on the margin's
    plane (z = 0, whatever its heights) off `relief`'s hinge, as `relief_of` reads a form's
    from its curves: a fold then eases the relief's turn as a form's does (bend.Pose's
    `fold_share`). Turned rigidly, a domed blade folded -75 (its margin 12-14° under the
    hinge) was fitted to -72.2 and 1.043 times its flat width (ovate), lanceolate 1.067."""
    clear = np.abs(boundary[:, 1]) > CREASE * np.abs(boundary[:, 1]).max()  # its own: a fitted
    # relief's half width is the margin's as posed (unfold_hinge), 0.26 of it folded 75°
    return _rise_fall(-relief.hinge_height(boundary[clear, 0]), boundary[clear, 1])


def _midrib(vein: np.ndarray, boundary: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The hinge's points: a midrib's (m, 3) points' x, increasing, and heights, with the
    outline's points on the crease (y = 0: a form's base, tip or notch) past the midrib's ends,
    at most MIDRIB_POINTS of them (every k-th, its ends kept), none within
    1e-6 of the extent of the one before; None when fewer than two are left. The hinge passes
    through each: a spline through 24 even knots missed an ovate form's midrib by 1.7e-3 of the
    length beside its base, and the fold's inverse took those points to the other half; a tip
    or a notch off the hinge is turned about it, and came back up to 9e-4 of the length away
    (cordate's notch, 7e-4 under the hinge's line)."""
    if len(vein) < 2:
        return None
    extent = float(np.ptp(boundary[:, 0]))
    x, z = _thinned(*_increasing(vein[:, 0], vein[:, 2], 1e-6 * extent))
    crease = boundary[np.abs(boundary[:, 1]) <= 1e-6 * extent]
    past = (crease[:, 0] < x[0] - 1e-6 * extent) | (crease[:, 0] > x[-1] + 1e-6 * extent)
    if past.any():
        x, z = _increasing(
            np.concatenate([x, crease[past, 0]]),
            np.concatenate([z, crease[past, 2]]),
            1e-6 * extent,
        )
    return (x, z) if len(x) >= 2 else None


def _thinned(x: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """At most MIDRIB_POINTS of a hinge's points: every k-th, its ends kept."""
    if len(x) <= MIDRIB_POINTS:
        return x, z
    step = int(np.ceil(len(x) / MIDRIB_POINTS))
    index = np.unique(np.append(np.arange(0, len(x), step), len(x) - 1))
    return x[index], z[index]


def _increasing(x: np.ndarray, z: np.ndarray, gap: float) -> tuple[np.ndarray, np.ndarray]:
    """Points' x and heights in x's order, none within `gap` of the one before."""
    order = np.argsort(x, kind="stable")
    x, z = x[order], z[order]
    keep = np.concatenate([[True], np.diff(x) > gap])
    return x[keep], z[keep]
