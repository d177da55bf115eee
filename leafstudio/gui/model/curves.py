"""The sketch's curves on the leaf plane, without Qt: splines through control points (the
boundary closed and periodic, each vein open) with centripetal parameters, which keep a spline
from looping between close points; arc lengths, even resampling, and where a new control point
goes. Sketch (sketch_model.py) draws its curves with these.
"""

from __future__ import annotations

import numpy as np
import shapely
from scipy.interpolate import CubicSpline, make_interp_spline

from leafstudio.core.prepare.polygon import unit_power

SAMPLES_PER_SPAN = 16  # curve points per span between two control points
MIN_BOUNDARY_SAMPLES = 120
DERIVED_BOUNDARY_POINTS = 24  # control points when a loaded leaf becomes a sketch


def _centripetal(points: np.ndarray) -> np.ndarray:
    """Cumulative centripetal parameter of (n, d) points (square root of chord lengths)."""
    steps = np.sqrt(np.linalg.norm(np.diff(points, axis=0), axis=1))
    return np.concatenate([[0.0], np.cumsum(steps)])


def _drop_repeats(points: np.ndarray, closed: bool) -> np.ndarray:
    """Control points without consecutive duplicates (a spline cannot pass twice in no time)."""
    return points[distinct(points, closed)]


def distinct(points: np.ndarray, closed: bool) -> np.ndarray:
    """(n,) mask of the (n, d) points a curve through them keeps: each not a repeat of the next
    (within 1e-12 of the points' extent), the last of a closed curve compared with the first."""
    keep = np.ones(len(points), dtype=bool)
    if len(points) < 2:
        return keep
    ahead = np.roll(points, -1, axis=0) if closed else points[1:]
    # within 1e-12 of the points' extent: an absolute 1e-12 took every point of a leaf at 1e-90
    # for a repeat, and the app's sketch of it failed ("zero-size array")
    tolerance = 1e-12 * float(np.max(points.max(axis=0) - points.min(axis=0)))
    same = np.all(np.abs(points[: len(ahead)] - ahead) <= tolerance, axis=1)
    keep[: len(ahead)] &= ~same
    return keep


def _span_samples(t: np.ndarray, per_span: int) -> np.ndarray:
    """Parameters spaced evenly within each span [t_i, t_i+1], every t_i included."""
    inner = np.linspace(0.0, 1.0, per_span, endpoint=False)
    return np.append((t[:-1, None] + np.diff(t)[:, None] * inner).ravel(), t[-1])


def _unit_factor(points: np.ndarray) -> float:
    """A power of two (exact) that brings the points' coordinates near 1 when they are beyond
    1e100 or under 1e-100, else 1: a spline through points at 1e300 overflowed (its chords'
    squares) and the app's sketch of such a leaf failed ("must contain only finite values")."""
    top = float(np.abs(points).max()) if points.size else 0.0
    return 1.0 if top == 0.0 or 1e-100 < top < 1e100 else unit_power(points)


def closed_curve(control: np.ndarray, per_span: int = SAMPLES_PER_SPAN) -> np.ndarray:
    """Points along the periodic cubic spline through (n, 2) control points, n >= 3.

    Returns
    -------
    (s, 2) float array
        Counter-ordered like the control points, without repeating the first point.
    """
    control = _drop_repeats(np.asarray(control, dtype=float), closed=True)
    if len(control) < 3:
        return control
    unit = _unit_factor(control)
    if unit != 1.0:
        return closed_curve(control * unit, per_span) / unit
    loop = np.vstack([control, control[:1]])
    t = _centripetal(loop)
    # CubicSpline, not make_interp_spline: for a periodic spline the latter solves by a
    # Woodbury update in Python, 3-9x slower here (0.7-2.5 vs 6-16 ms; the same curve to 1e-15)
    spline = CubicSpline(t, loop, bc_type="periodic")
    per_span = max(per_span, -(-MIN_BOUNDARY_SAMPLES // len(control)))
    return spline(_span_samples(t, per_span)[:-1])


def open_curve(control: np.ndarray, per_span: int = SAMPLES_PER_SPAN) -> np.ndarray:
    """Points along the natural cubic spline through (m, d) control points (a line for m = 2)."""
    control = _drop_repeats(np.asarray(control, dtype=float), closed=False)
    if len(control) < 2:
        return control
    unit = _unit_factor(control)
    if unit != 1.0:
        return open_curve(control * unit, per_span) / unit
    t = _centripetal(control)
    s = _span_samples(t, per_span)
    if len(control) == 2:
        return control[0] + np.outer(s / t[-1], control[1] - control[0])
    # the same spline as CubicSpline's to rounding, made in half its time (13 veins of a new
    # document's sketch: 12 -> 6 ms on the main thread)
    return make_interp_spline(t, control, k=3, bc_type="natural")(s)


def nearest_on_polyline(curve: np.ndarray, xy: np.ndarray) -> tuple[np.ndarray | None, float]:
    """The point of the (s, d) polyline `curve` nearest plane point `xy` (in x, y; its other
    columns interpolated) and its distance: (None, inf) for an empty curve."""
    if len(curve) == 0:
        return None, np.inf
    if len(curve) == 1:
        candidates = curve
    else:  # the nearest point on each segment
        a, b = curve[:-1], curve[1:]
        ab = b[:, :2] - a[:, :2]
        along = np.einsum("ij,ij->i", xy - a[:, :2], ab) / np.maximum((ab**2).sum(1), 1e-300)
        candidates = a + np.clip(along, 0, 1)[:, None] * (b - a)
    d = np.linalg.norm(candidates[:, :2] - xy, axis=1)
    j = int(np.argmin(d))
    return np.asarray(candidates[j], dtype=float), float(d[j])


def plane_arc_lengths(points: np.ndarray) -> np.ndarray:
    """(n,) length along the (n, d) points' polyline, in the plane (x, y), from the first."""
    steps = np.linalg.norm(np.diff(points[:, :2], axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(steps)])


def _even_indices(points: np.ndarray, count: int, closed: bool) -> np.ndarray:
    """Indices of `count` of the (n, d) points spread evenly by arc length (in the plane)."""
    path = np.vstack([points, points[:1]]) if closed else points
    arc = plane_arc_lengths(path)
    targets = np.linspace(0.0, arc[-1], count, endpoint=not closed)
    return np.unique(np.clip(np.searchsorted(arc, targets), 0, len(points) - 1))


def even_by_length(points: np.ndarray, count: int, closed: bool) -> np.ndarray:
    """`count` of the (n, d) points spread evenly by arc length along them (indices kept)."""
    return points[_even_indices(points, count, closed)]


OUTLINE_TOLERANCE = 0.005  # a derived boundary's spline stays this close (of the extent) to it


def outline_controls(polygon: np.ndarray) -> np.ndarray:
    """Control points whose closed spline follows the (n, 2) outline polygon within
    OUTLINE_TOLERANCE of its extent: the corners the outline's Douglas-Peucker simplification
    keeps (tooth tips, sinuses), among points spread evenly along it, more of them until the
    spline is close enough. An even spread alone (24 points) smoothed every tooth away."""
    polygon = np.asarray(polygon, dtype=float)
    extent = float(np.ptp(polygon, axis=0).max()) if len(polygon) else 0.0
    if len(polygon) <= DERIVED_BOUNDARY_POINTS or extent == 0.0:
        return polygon
    tolerance = OUTLINE_TOLERANCE * extent
    corners = shapely.get_coordinates(shapely.simplify(shapely.LinearRing(polygon), tolerance))
    # the corners are some of the polygon's own points: find them as complex keys, not in a dict
    keys = polygon[:, 0] + 1j * polygon[:, 1]
    keep = np.flatnonzero(np.isin(keys, corners[:, 0] + 1j * corners[:, 1]))
    count = DERIVED_BOUNDARY_POINTS
    while True:
        chosen = np.union1d(keep, _even_indices(polygon, count, closed=True))
        control = polygon[chosen]
        if len(chosen) == len(polygon) or np.all(
            _span_distances(polygon, chosen, closed_curve(control)) <= 2 * tolerance
        ):
            return control
        count *= 2


def _span_distances(polygon: np.ndarray, chosen: np.ndarray, curve: np.ndarray) -> np.ndarray:
    """(n,) distance of each of the (n, 2) polygon's points to the span of the closed spline
    `curve` (closed_curve of polygon[chosen], chosen sorted) between the two control points the
    point lies between: at least its distance to the whole curve, so a check that passes on it
    passes on the curve; n times a span's samples, where the whole curve's distance was n times
    all its samples (20 ms for a 4000-point outline, on the main thread when a file opens)."""
    spans = len(chosen)
    if len(curve) % spans:  # closed_curve dropped a repeated control point: no span per pair
        return shapely.distance(shapely.points(polygon), shapely.LinearRing(curve))
    per_span = len(curve) // spans
    ring = np.vstack([curve, curve[:1]])
    span = (np.searchsorted(chosen, np.arange(len(polygon)), side="right") - 1) % spans
    starts = span[:, None] * per_span + np.arange(per_span)  # (n, per_span) segment starts
    a, b = ring[starts], ring[starts + 1]
    ab, ap = b - a, polygon[:, None, :] - a
    length2 = np.einsum("nkd,nkd->nk", ab, ab)
    along = np.clip(np.einsum("nkd,nkd->nk", ap, ab) / np.where(length2 > 0, length2, 1), 0, 1)
    off = ap - along[..., None] * ab
    return np.sqrt(np.einsum("nkd,nkd->nk", off, off).min(axis=1))


def insert_index(control: np.ndarray, xy: np.ndarray, closed: bool) -> int:
    """Where a new point `xy` belongs in the control polygon: the place that lengthens it least.

    Between two neighbours a and b that costs |a - p| + |p - b| - |a - b|; an open curve may also
    grow at either end, costing the distance to that end. Clicking around an outline in order
    thus appends, and clicking beside a span inserts into it.
    """
    control = np.asarray(control, dtype=float)[:, :2]
    n = len(control)
    if n < 2:
        return n
    a = control if closed else control[:-1]
    b = np.roll(control, -1, axis=0) if closed else control[1:]
    dist = lambda p, q: np.linalg.norm(p - q, axis=-1)  # noqa: E731
    costs = dist(a, xy) + dist(xy, b) - dist(a, b)
    best = int(np.argmin(costs))
    if not closed:
        ends = (dist(control[0], xy), dist(control[-1], xy))
        if min(ends) < costs[best]:
            return 0 if ends[0] < ends[1] else n
    return best + 1
