"""What core/unfold.py asks of curves given in 3D before and while it fits a pose: whether the
margin is bent enough to try (off its PCA plane, or off the best quadratic height field over it),
whether the leaf as given is refused (a vein outside the outline where the boundary's plane sees
it side-on, the outline crossing itself there), and whether a pose lays it flat."""

from __future__ import annotations

import numpy as np
import shapely
from scipy.spatial import cKDTree

from leafstudio.core.placed import PlacedPose
from leafstudio.core.plane import fit_frame
from leafstudio.core.prepare.outline import ordered_crossing
from leafstudio.core.prepare.vein_order import veins_inside_outline
from leafstudio.model import Leaf

OFF_PLANE = 0.06  # a margin this far off its PCA plane (RMS, share of its RMS width) may be bent
# (0.2 left an ovate form folded 45 degrees and curled 0.5 unbent, 0.17: its curl on a circle).
# At 0.12 a bowl curled and rolled up, whose midrib does not sink (FORESHORTENED: 1.02), ran as a
# height field: ovate curled 0.5 and rolled 0.3 (0.104; serrate 0.092) 1.9% and 3.4% narrow as
# CSVs, curled 0.3 and rolled 0.2 (0.076) 2.4% wide, folded 10 (0.076) 2.8% wide; fitted, each
# its own pose (pose37). A cup (a quadratic height field, 0.066-0.10 off at 0.3 of the length
# deep) is fitted too, 1.8-2.4 s of CPU once, and refused (no pose lays it flatter than the quadric:
# unfold.EXPLAINED); the app's document keeps the refusal for its sketch edits
# (gui/model/bending.keeps_refusal; review37b had found each edit fitted again)
OFF_QUADRIC = 0.025  # ... and so may one this far off its best quadratic height field: a fold
# down and a roll up nearly cancel off the plane (fold -45 roll 0.4: 0.044-0.11 off it, under
# OFF_PLANE) but not off the quadric (0.027-0.094, elliptic's 0.007): ten of the 14 shapes so
# posed were 2.4e-3-9.7e-3 of the length off their own surface at p95 as height fields, nine of
# them now unfolded 0.9e-3-2.7e-3 (oblanceolate 1.7e-3 -> 3.3e-3). Folded 10 the quadric leaves
# 0.002-0.019, curled 0.2 at most 0.001: they run as before
FORESHORTENED = 1.1  # ... or, a margin under both, when its midrib is this many times as long as
# its shadow on the margin's PCA plane: a blade curled and rolled one way is a bowl whose rim
# lies nearly on a plane (reniform curled -1 and rolled -0.3: 0.117 of its width off it, 0.016 off
# the quadric) and whose midrib sinks under it, 1.40 times its shadow (curled -0.5: 1.15); it ran
# as a height field 26.5% short. Flat gallery forms' domes give 1.0005-1.036, the drawn and clicked
# leaves of bench_bent --veins 1.012 and 1.011, waved forms 1.05-1.08 (/work/notes/pose36)
RIM_ON_PLANE = 1e-3  # ... and its margin off its PCA plane by more than this share of its RMS
# width: a margin on its plane to rounding is no bowl's rim but a drawn leaf's (its relief flat:
# 0), whose midrib the side view may lift (the clicked leaf's tip raised 0.5: 1.17 times its
# shadow; each edit then ran the fit, 0.95 s CPU, to none, and a refusal called it "bent in 3D ...
# a posed or scanned leaf saved as a point list", review36). The foreshortened bowls' rims: at
# least 3.9e-3 (orbicular curled -0.4, rolled -0.15; reniform 0.036, a grid of curls and rolls)
SHADOW_POINTS = 16  # ... the midrib taken at about this many points: digitising noise lengthens
# a densely sampled curve off the plane and on it alike, not its chords
SMOOTHING = np.array([-2.0, 3.0, 6.0, 7.0, 6.0, 3.0, -2.0]) / 21  # a quadratic's least squares
# over seven neighbours, at the middle one (Savitzky-Golay): what is left of a point's own noise
# is 2/3 of it in variance, each axis
NOISE_KEPT = 0.9  # ... the least this share of what is left, squared, across the blade (the
# apex's and base's corners not taken for noise), whose mean is this times the noise's variance:
NOISE_MEAN = 0.6230 * 2 / 3  # chi-square of 1 degree below its 90th percentile, 0.6230. Their
# median read elliptic folded 40 with 5e-4 of the length 0.86 of it, and its fit was refused
# for 1 of 8 seeds (0.89-1.13 of it over five seeds on others); a serrate form's teeth read as
# 4e-5-8e-5 of the length there, in this mean 1.1e-4 (/work/notes/pose36/probe_noise.py)
NOISE_FLOOR = 1e-5  # ... none under this share of the ring's diagonal: the gallery's forms as
# 9-digit CSVs read 0-1.9e-6 (waved), their fits as before; toothed forms 3.7e-5-1.1e-4 (their
# teeth; with 5e-4 of noise added, 4.3e-4-5.0e-4 is read: /work/notes/pose36/probe_noise.py)
NOISE_SPREAD = 3.0  # ... and a fit's rms is taken beyond the noise past its mean share by this
# many of its standard deviations (a mean square over d heights scatters sqrt(2 / d) of itself:
# over a thinned margin's 60, 0.18), as the noise read scatters too: elliptic folded 40, given
# 5e-4 of the length, is unfolded when its fold about the hinge leaves 6.2e-5 beyond it
VEINS_OUT = 0.02  # an unfolding that leaves more of the veins' points outside the outline is wrong
SIDE_ON = 0.01  # a whole vein this share of the length outside the outline on the boundary's
# plane (the pipeline refuses it past 0.01: steps.VEIN_OUTSIDE_TOLERANCE): the plane is side-on


def off_plane(points: np.ndarray) -> tuple[float, float]:
    """RMS distance of (n, 3) points from their PCA plane, and their RMS spread across (the
    second)."""
    return _pca(points)[:2]


def _pca(points: np.ndarray) -> tuple[float, float, np.ndarray]:
    """`off_plane`'s two spreads of (n, 3) points, and their PCA plane's normal (3,)."""
    centred = points - points.mean(axis=0)
    values, vectors = np.linalg.eigh(centred.T @ centred / len(points))
    spreads = np.sqrt(np.maximum(values, 0))
    return float(spreads[0]), float(spreads[1]), vectors[:, 0]


def off_quadric(points: np.ndarray) -> float:
    """RMS distance of (n, 3) points from the quadratic height field over their PCA plane that
    fits them best: what the paper's base b(x) already takes (a cupped or gently curled margin)."""
    centred = points - points.mean(axis=0)
    axes = np.linalg.eigh(centred.T @ centred)[1][:, ::-1]
    x, y, z = (centred @ axes).T
    design = np.column_stack([np.ones_like(x), x, y, x * x, x * y, y * y])
    fit = np.linalg.lstsq(design, z, rcond=None)[0]
    return float(np.sqrt(np.mean((design @ fit - z) ** 2)))


def bent(boundary: np.ndarray, midrib: np.ndarray | None = None) -> bool:
    """Whether a margin's (n, 3) points are bent enough for a pose to be fitted: well off their
    PCA plane (OFF_PLANE), or off it and off the best quadratic height field (OFF_QUADRIC; the
    quadric's rms is at most the plane's: a flat leaf does not fit it), or, given the (m, 3)
    `midrib`, that sunk under the margin's plane as a bowl's (FORESHORTENED) whose rim is not
    drawn on it (RIM_ON_PLANE)."""
    before, width, normal = _pca(boundary)
    if before > OFF_PLANE * width:
        return True
    if before > OFF_QUADRIC * width and off_quadric(boundary) > OFF_QUADRIC * width:
        return True
    if midrib is None or before <= RIM_ON_PLANE * width:
        return False
    return foreshortened(midrib, normal) > FORESHORTENED


def foreshortened(midrib: np.ndarray, normal: np.ndarray) -> float:
    """How many times the (m, 3) `midrib` (at about SHADOW_POINTS points) is as long as its
    shadow on a plane of unit (3,) `normal`: 1 for a midrib on that plane, and for one of no
    length (a vein of one point, as a click starts one: it has no length to lose, and a flat
    leaf so given was called bent in 3D, its refusal told of a pose it never had)."""
    points = np.vstack([midrib[:: max(1, len(midrib) // SHADOW_POINTS)], midrib[-1:]])
    steps = np.diff(points, axis=0)
    squares = np.einsum("ij,ij->i", steps, steps)
    along = float(np.sqrt(squares).sum())
    shadow = float(np.sqrt(np.maximum(squares - (steps @ normal) ** 2, 0.0)).sum())
    if along == 0:
        return 1.0
    return along / shadow if shadow > 0 else np.inf


def margin_noise(boundary: np.ndarray, midrib: np.ndarray) -> float:
    """The digitising noise of the (n, 3) ring `boundary`, each axis (the noise's standard
    deviation): its points off a quadratic through their neighbours (SMOOTHING), across the
    blade there (the margin's tangent crossed with the way to the (m, 3) `midrib`'s nearest
    point: a tooth's corner, which lies in the blade, is not taken for noise), their mean
    (NOISE_KEPT, NOISE_MEAN); 0 under NOISE_FLOOR, or for fewer than seven points."""
    if len(boundary) < len(SMOOTHING) or len(midrib) < 2:
        return 0.0
    half = len(SMOOTHING) // 2
    ring = np.concatenate([boundary[-half:], boundary, boundary[:half]])
    smooth = sum(w * ring[i : i + len(boundary)] for i, w in enumerate(SMOOTHING))
    tangent = ring[2 * half :] - ring[: -2 * half]
    inward = midrib[cKDTree(midrib).query(boundary)[1]] - boundary
    across = np.cross(tangent, inward)
    size = np.linalg.norm(across, axis=1)
    keep = size > 0
    if not keep.any():
        return 0.0
    left = np.einsum("ij,ij->i", (boundary - smooth)[keep], across[keep]) / size[keep]
    left = np.sort(left * left)[: max(1, int(NOISE_KEPT * len(left)))]
    noise = float(np.sqrt(np.mean(left) / NOISE_MEAN))
    return noise if noise > NOISE_FLOOR * float(np.linalg.norm(np.ptp(boundary, axis=0))) else 0.0


def above_noise(rms: float, noise: float, free: int, points: int) -> float:
    """What a fit of `free` numbers to `points` heights leaves (`rms`) beyond the margin's
    digitising `noise` (each axis, `margin_noise`), which no pose lays flat: of its variance the
    fit leaves 1 - free / points (NOISE_SPREAD). With a CSV's points 5e-4 of the length off
    (pose36), elliptic folded 40, whose quadric leaves 1.3e-3, was fitted none (7.3% narrow),
    ovate curled 0.5 none, and unfold_mixed ran on every noisy leaf (MIXED_FROM)."""
    dof = max(points - free, 1)
    share = dof / points * (1 + NOISE_SPREAD * np.sqrt(2 / dof))
    return float(np.sqrt(max(rms * rms - noise * noise * share, 0.0)))


def lies_flat(bend: PlacedPose, leaf: Leaf) -> bool:
    """Whether `bend` unfolds `leaf` into a blade: its outline not crossing itself, and the
    veins' points inside it (all but VEINS_OUT of them)."""
    flat = bend.frame.to_plane(bend.flat_curve(leaf.boundary, ring=True))[0]
    if not shapely.LinearRing(flat).is_simple:
        return False
    region = shapely.Polygon(flat).buffer(1e-3 * float(np.ptp(flat, axis=0).max()))
    veins = bend.frame.to_plane(np.vstack([bend.flat_curve(v) for v in leaf.veins]))[0]
    return bool(np.mean(~shapely.contains_xy(region, veins[:, 0], veins[:, 1])) <= VEINS_OUT)


def side_on(leaf: Leaf, length: float) -> bool:
    """Whether the boundary's PCA plane sees `leaf` side-on: a whole vein (all but a point)
    lies outside the outline there, by more than SIDE_ON of `length` (forms/make.seen_on_edge).
    Veins of fewer than three points are not asked: one of a single point has no second point
    inside, and made a cupped leaf "side-on" (a pose fitted to a leaf that needs none)."""
    veins = [v for v in leaf.veins if len(v) >= 3]
    return len(veins_inside_outline(leaf.boundary, veins, -SIDE_ON * length)) < len(veins)


def crosses(leaf: Leaf) -> bool:
    """Whether `leaf`'s boundary, in its order, crosses itself on the boundary's PCA plane: the
    app and the commands refuse it as given (outline.ordered_crossing)."""
    frame = fit_frame(leaf.boundary, leaf.vein_points)
    return ordered_crossing(frame.to_plane(leaf.boundary)[0]) is not None


def simplest(fits: list[tuple], ratio: float, slack: float) -> tuple:
    """Of `fits` ((rms, terms, ...) each), the one of fewest terms that leaves at most `ratio`
    times the best's rms plus `slack` (unfold.py's fits, unfold_mixed's): a fold mimicked by a
    roll and a curl is not taken for one."""
    enough = ratio * min(f[0] for f in fits) + slack
    return min(fits, key=lambda f: (f[0] > enough, len(f[1])))
