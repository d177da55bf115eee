"""What core/unfold.py asks of curves given in 3D before and while it fits a pose: whether the
margin is bent enough to try (off its PCA plane, or off the best quadratic height field over it),
whether the leaf as given is refused (a vein outside the outline where the boundary's plane sees
it side-on, the outline crossing itself there), and whether a pose lays it flat."""

from __future__ import annotations

import numpy as np
import shapely

from leafstudio.core.placed import PlacedPose
from leafstudio.core.plane import fit_frame
from leafstudio.core.prepare.outline import ordered_crossing
from leafstudio.core.prepare.vein_order import veins_inside_outline
from leafstudio.model import Leaf

OFF_PLANE = 0.12  # a margin this far off its PCA plane (RMS, share of its RMS width) may be bent
# (0.2 left an ovate form folded 45 degrees and curled 0.5 unbent, 0.17: its curl on a circle)
OFF_QUADRIC = 0.025  # ... and so may one this far off its best quadratic height field: a fold
# down and a roll up nearly cancel off the plane (fold -45 roll 0.4: 0.044-0.11 off it, under
# OFF_PLANE) but not off the quadric (0.027-0.094, elliptic's 0.007): ten of the 14 shapes so
# posed were 2.4e-3-9.7e-3 of the length off their own surface at p95 as height fields, nine of
# them now unfolded 0.9e-3-2.7e-3 (oblanceolate 1.7e-3 -> 3.3e-3). Folded 10 the quadric leaves
# 0.002-0.019, curled 0.2 at most 0.001: they run as before
VEINS_OUT = 0.02  # an unfolding that leaves more of the veins' points outside the outline is wrong
SIDE_ON = 0.01  # a whole vein this share of the length outside the outline on the boundary's
# plane (the pipeline refuses it past 0.01: steps.VEIN_OUTSIDE_TOLERANCE): the plane is side-on


def off_plane(points: np.ndarray) -> tuple[float, float]:
    """RMS distance of (n, 3) points from their PCA plane, and their RMS spread across (the
    second)."""
    centred = points - points.mean(axis=0)
    spreads = np.sqrt(np.maximum(np.linalg.eigvalsh(centred.T @ centred / len(points)), 0))
    return float(spreads[0]), float(spreads[1])


def off_quadric(points: np.ndarray) -> float:
    """RMS distance of (n, 3) points from the quadratic height field over their PCA plane that
    fits them best: what the paper's base b(x) already takes (a cupped or gently curled margin)."""
    centred = points - points.mean(axis=0)
    axes = np.linalg.eigh(centred.T @ centred)[1][:, ::-1]
    x, y, z = (centred @ axes).T
    design = np.column_stack([np.ones_like(x), x, y, x * x, x * y, y * y])
    fit = np.linalg.lstsq(design, z, rcond=None)[0]
    return float(np.sqrt(np.mean((design @ fit - z) ** 2)))


def bent(boundary: np.ndarray) -> bool:
    """Whether a margin's (n, 3) points are bent enough for a pose to be fitted: well off their
    PCA plane (OFF_PLANE), or off it and off the best quadratic height field (OFF_QUADRIC; the
    quadric's rms is at most the plane's: a flat leaf does not fit it)."""
    before, width = off_plane(boundary)
    if before > OFF_PLANE * width:
        return True
    return before > OFF_QUADRIC * width and off_quadric(boundary) > OFF_QUADRIC * width


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
