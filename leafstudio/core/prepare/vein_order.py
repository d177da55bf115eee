"""The order of a vein's points: kept when they run along the vein, made canonical when not.

The pipeline thins dense veins along their order (polygon.thin_veins, height.height_guide) and
picks vein rows for the surface fit evenly by index, so a shuffled vein used to be thinned to a
random few of its points (a 1e5-point vein's mean distance to the mesh tripled). A vein whose
path through its points in the given order is no longer than a few times its extent is taken as
ordered and kept; any other (shuffled, or dense and noisy) is sorted along its principal axis, a
canonical order of the point set: any shuffle of the same points gives the same order.
"""

from __future__ import annotations

import numpy as np
import shapely

from leafstudio.core.buckets import bounds, kernel_array
from leafstudio.core.jit import njit
from leafstudio.core.plane import fit_frame

ORDERED_PATH = 4.0  # an ordered vein's path is at most this many times its box's diagonal
ROUNDING = 1e-8  # vein_orders' path, summed in order, is this near numpy's pairwise sum


def vein_order(xy: np.ndarray) -> np.ndarray:
    """(m,) indices putting a vein's (m, 2) plane points in order along it (see the module)."""
    xy = np.asarray(xy, dtype=float)
    if len(xy) < 3:
        return np.arange(len(xy))
    path = float(np.sqrt((np.diff(xy, axis=0) ** 2).sum(axis=1)).sum())
    lo, hi = bounds(xy, lambda p: (p.min(axis=0), p.max(axis=0)))  # np.ptp's, quicker
    if path <= ORDERED_PATH * float(np.hypot(*(hi - lo))):
        return np.arange(len(xy))
    centred = xy - xy.mean(axis=0)
    axis = np.linalg.eigh(centred.T @ centred)[1][:, -1]
    axis = axis if axis[np.argmax(np.abs(axis))] > 0 else -axis  # a sign of its own
    return np.lexsort((xy[:, 1], xy[:, 0], xy @ axis))


def vein_orders(veins: list[np.ndarray]) -> list[np.ndarray]:
    """vein_order of each of the (m_i, 2) veins. The veins in order already (nearly always) are
    found in one compiled pass (`_in_order`: a flat ovate's 13 veins, 0.15 -> 0.014 ms, best
    of 200); one whose path, summed in order rather than by numpy's pairwise sum, comes within
    ROUNDING of the threshold or past it is left to vein_order, so the orders are its own."""
    if not veins:
        return []
    sizes = np.array([len(v) for v in veins], dtype=np.int64)
    ordered = _in_order(kernel_array(np.vstack(veins)), sizes, ORDERED_PATH * (1 - ROUNDING))
    return [
        np.arange(len(v)) if ok else vein_order(v) for v, ok in zip(veins, ordered, strict=True)
    ]


@njit(cache=True, nogil=True)
def _in_order(xy, sizes, most):
    """(k,) bool: for the veins of `sizes` points one after another in the (n, 2) `xy`, whether
    each has fewer than 3 points or a path no longer than `most` times its box's diagonal (a NaN
    makes the path NaN: False; an inf point can make both inf: True, as vein_order's own test)."""
    ordered = np.zeros(len(sizes), np.bool_)
    start = 0
    for v in range(len(sizes)):
        end = start + sizes[v]
        if sizes[v] < 3:
            ordered[v] = True
        else:
            path = 0.0
            lo_x = hi_x = xy[start, 0]
            lo_y = hi_y = xy[start, 1]
            for i in range(start + 1, end):
                x, y = xy[i, 0], xy[i, 1]
                dx, dy = x - xy[i - 1, 0], y - xy[i - 1, 1]
                path += np.sqrt(dx * dx + dy * dy)
                lo_x, hi_x = min(lo_x, x), max(hi_x, x)
                lo_y, hi_y = min(lo_y, y), max(hi_y, y)
            ordered[v] = path <= most * np.hypot(hi_x - lo_x, hi_y - lo_y)
        start = end
    return ordered


def veins_inside_outline(
    boundary: np.ndarray, veins: list[np.ndarray], gap: float
) -> list[np.ndarray]:
    """The (m_i, 3) veins' points that lie inside the (n, 3) boundary by at least `gap` (or
    outside it by at most -gap, when negative), as the pipeline sees them: on the boundary's own
    PCA plane, where a curled or folded margin moves (a vein drawn inside the flat outline can
    fall outside it there). Veins left with fewer than two points are dropped."""
    if not veins:
        return []
    frame = fit_frame(boundary, np.vstack(veins))
    region = shapely.Polygon(frame.to_plane(boundary)[0]).buffer(-gap)
    kept = []
    for vein in veins:
        xy = frame.to_plane(vein)[0]
        inside = vein[shapely.contains_xy(region, xy[:, 0], xy[:, 1])]
        if len(inside) >= 2:
            kept.append(inside)
    return kept


SIDE_VEINS = 4  # side veins needed before their lean says which end of the midrib is the base
LEAN_SHARE = 0.8  # of those leaning clearly, the share that must lean the same way
ATTACHED = 0.05  # a side vein's nearer end within this share of the midrib's length from it
LEAVES = 0.05  # its farther end at least this share away (it leaves the midrib: not parallel)
LEAN = 0.02  # it leans when its far end is this share of the length along the midrib
INNER = 0.1  # only veins leaving the midrib this share of its length or more from its ends


def midrib_lean(midrib: np.ndarray, side: list[np.ndarray]) -> tuple[int, int]:
    """How many of a midrib's (k_i, 2) `side` veins lean clearly toward its first point, and
    how many lean clearly either way, its (m, 2) points and theirs in the leaf's plane: a side
    vein that leaves the midrib (its nearer end on it, away from its ends, the farther well off
    it) leans toward the apex. Veins that run beside it (parallel venation), meet it at an end
    (palmate primaries) or do not touch it are not counted."""
    if len(midrib) < 2:
        return 0, 0
    first = midrib[0]
    midrib = midrib[vein_order(midrib)]  # a shuffled midrib's first point means nothing
    if np.linalg.norm(midrib[-1] - first) < np.linalg.norm(midrib[0] - first):
        midrib = midrib[::-1]  # put in order, it starts at the written first point's end
    chord = midrib[-1] - midrib[0]
    length = float(np.linalg.norm(chord))
    if not length > 0:
        return 0, 0
    along = chord / length
    line = shapely.LineString(midrib)
    side = [vein for vein in side if len(vein) >= 2]
    # every side vein's two ends measured in one call: midrib_turned on a gallery ovate (13
    # veins) 0.29 -> 0.25 ms, best of 60
    ends = np.array([vein[[0, -1]] for vein in side]).reshape(-1, 2)
    all_gaps = shapely.distance(line, shapely.points(ends)).reshape(-1, 2)
    leans = []
    for vein, gaps in zip(side, all_gaps, strict=True):
        near, far = (vein[0], vein[-1]) if gaps[0] <= gaps[1] else (vein[-1], vein[0])
        if gaps.min() > ATTACHED * length or gaps.max() < max(LEAVES * length, 3 * gaps.min()):
            continue
        if not INNER < float((near - midrib[0]) @ along) / length < 1 - INNER:
            continue
        lean = float((far - near) @ along) / length
        if abs(lean) > LEAN:
            leans.append(lean)
    return sum(lean < 0 for lean in leans), len(leans)


def leans_back(back: int, leaning: int) -> bool:
    """Whether a midrib runs from the apex to the base, by midrib_lean's counts: at least
    SIDE_VEINS side veins lean clearly and LEAN_SHARE of them toward its first point. A basal
    lobe's veins leaning back (sagittate) leave too few agreeing: nothing is claimed. On the
    gallery's forms (14 shapes, 4 venations, 6 seeds) no midrib written base first is claimed,
    and 160 of the 336 written apex first are found (148 of the 168 pinnate and arcuate ones).

    Examples
    --------
    >>> leans_back(5, 6), leans_back(4, 6), leans_back(3, 3)
    (True, False, False)
    """
    return leaning >= SIDE_VEINS and back >= LEAN_SHARE * leaning


def midrib_leaning(veins: list[np.ndarray]) -> tuple[int, int]:
    """midrib_lean's counts for vein 1 of the (m_i, 3) `veins`, its side veins seen on the
    veins' own plane (at unit size: a leaf at 1e200 squares to inf); (0, 0) for too few veins."""
    if len(veins) <= SIDE_VEINS or len(veins[0]) < 2:
        return 0, 0
    points = np.vstack(veins)
    centre = points.mean(axis=0)
    size = float(np.abs(points - centre).max())
    if not (np.isfinite(size) and size > 0):
        return 0, 0
    unit = (points - centre) / size
    axes = np.linalg.eigh(unit.T @ unit)[1][:, :0:-1]  # the veins' plane, widest first
    plane = [(vein - centre) / size @ axes for vein in veins]
    return midrib_lean(plane[0], plane[1:])


def midrib_turned(veins: list[np.ndarray]) -> bool:
    """Whether vein 1 of the (m_i, 3) flat `veins` runs from the apex to the base (leans_back of
    midrib_leaning): every reader of its base (the length, the placement, the app's bending
    frame, veins grown from it, the warning that says so) decides it alike."""
    return leans_back(*midrib_leaning(veins))
