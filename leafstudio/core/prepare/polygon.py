"""Polygon tools the stages share: repeats dropped, outlines and veins thinned, outward normals,
the compiled inside test, self-crossings. The outline itself is traced in outline.py; these take
a polygon (or points along a curve) already in order.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from leafstudio.core.buckets import bounds, kernel_array, neighbour_distances
from leafstudio.core.jit import njit

MAX_OUTLINE_VERTICES = 3000  # a denser outline is thinned to about this many (thin_outline)
APART_SEARCHED = 10_000  # points, at most, that _apart_in_the_plane searches before the tree


def unit_power(points: np.ndarray) -> float:
    """The power of two that brings the points' largest coordinate into [0.5, 1): a scale
    that loses no digit, for work whose squares overflow or underflow far from 1."""
    top = float(np.abs(points).max()) if np.size(points) else 0.0
    return float(2.0 ** -np.frexp(max(top, 1e-300))[1])


def distinct_indices(points: np.ndarray, scale: float) -> np.ndarray:
    """Indices of the (n, 2) or (n, 3) points left once repeats are dropped, in order: of points
    within 1e-9 of `scale` of one another (in chains), the first. By distance, not by rounding to a
    grid of 1e-9: copies 5e-12 apart that fell either side of a rounding boundary were both
    kept, and a noisy outline moved by 0.75% of its length (issue 24, finding 19). scipy's
    cKDTree finds the pairs (measured once, on a busy 2-core machine, on a ring of 2.4M points
    with 20% copies: 1.5 s, as the sort by grid keys it replaced; 0.28 s against 0.14 s on 360k)."""
    n = len(points)
    if n == 0:
        return np.arange(0)
    # scaled by a power of two (exact) to at most 1: a vein point at 1e200 overflowed the tree
    unit = unit_power(points)
    reach = 1e-9 * scale * unit
    if _apart_along_an_axis(points * unit, reach) or _apart_in_the_plane(points * unit, reach):
        return np.arange(n)
    pairs = cKDTree(points * unit).query_pairs(reach, output_type="ndarray")
    if not len(pairs):
        return np.arange(n)
    links = coo_matrix((np.ones(len(pairs), dtype=bool), (pairs[:, 0], pairs[:, 1])), (n, n))
    _, group = connected_components(links, directed=False)
    return np.sort(np.unique(group, return_index=True)[1])


def distinct_each(curves: list[np.ndarray], scale: float) -> list[np.ndarray]:
    """distinct_indices of each of the (m_i, 2) curves. Those whose points are all apart along
    an axis (nearly every vein) are found in one compiled pass, the same test to the bit
    (`_apart_each`: a flat ovate's 13 veins, 0.13 -> 0.014 ms, best of 200); the rest are left to
    distinct_indices."""
    if not curves:
        return []
    sizes = np.array([len(c) for c in curves], dtype=np.int64)
    apart = _apart_each(kernel_array(np.vstack(curves)), sizes, float(scale))
    return [
        np.arange(len(c)) if ok else distinct_indices(c, scale)
        for c, ok in zip(curves, apart, strict=True)
    ]


@njit(cache=True, nogil=True)
def _apart_each(xy, sizes, scale):
    """(k,) bool: for the curves of `sizes` points one after another in the (n, 2) `xy`, whether
    distinct_indices would find each apart along an axis at once (unit_power's scale, then
    _apart_along_an_axis, in the same arithmetic; an inf: False, left to it; a NaN fails its own
    axis, as there, but numba's max leaves it out of the scale)."""
    apart = np.zeros(len(sizes), np.bool_)
    start = 0
    for c in range(len(sizes)):
        n = sizes[c]
        end = start + n
        top = 0.0
        for i in range(start, end):
            top = max(top, abs(xy[i, 0]), abs(xy[i, 1]))
        if n < 2:
            apart[c] = True
        elif np.isfinite(top):
            unit = 2.0 ** -math.frexp(max(top, 1e-300))[1]
            limit = 1e-9 * scale * unit * (1 + 1e-6)
            column = np.empty(n)
            for axis in range(2):
                for i in range(n):
                    column[i] = xy[start + i, axis] * unit
                _shell_sort(column)
                spread = True
                for i in range(n - 1):
                    if not column[i + 1] - column[i] > limit:
                        spread = False
                        break
                if spread:
                    apart[c] = True
                    break
        start = end
    return apart


@njit(cache=True, nogil=True)
def _shell_sort(values):
    """Sort the (n,) `values` in place: Shell's sort (Knuth's gaps), about linear on a vein's
    coordinates, nearly in order along it (with numpy's sort _apart_each took 3.0 s of the first
    run's compile, with this 1.2 s; as edges._edge_table sorts its buckets)."""
    n = len(values)
    gap = 1
    while gap < n // 3:
        gap = 3 * gap + 1
    while gap > 0:
        for i in range(gap, n):
            x, j = values[i], i - gap
            while j >= 0 and values[j] > x:
                values[j + gap] = values[j]
                j -= gap
            values[j + gap] = x
        gap //= 3


def _apart_in_the_plane(points: np.ndarray, reach: float) -> bool:
    """Whether each of the (n, 2) finite points' nearest other lies more than `reach` (with a
    margin of 1e-6 of it) away, by the bucket search: then no two lie within `reach` and no k-d
    tree need look (a flat ovate's 502 outline points, whose mirrored halves share their x and
    whose ordinates repeat: cKDTree's query_pairs 0.20 ms, this 0.08, on a busy host,
    /work/notes/cpu39/micro_distinct.py). (n, 3) points, and more than APART_SEARCHED (a cloud
    with repeats would pay the search besides its tree, unmeasured there): the tree."""
    if points.ndim != 2 or points.shape[1] != 2 or not 2 <= len(points) <= APART_SEARCHED:
        return False
    if not np.isfinite(points).all():
        return False
    nearest = neighbour_distances(points, np.arange(len(points)))
    return bool(nearest.min() > reach * (1 + 1e-6))


def _apart_along_an_axis(points: np.ndarray, reach: float) -> bool:
    """Whether the (n, 2) points, sorted along x or along y, are each more than `reach` (with a
    margin of 1e-6 of it) from the next: then no two lie within `reach` of one another, and no
    k-d tree need look (a flat ovate's 13 veins: 0.215 -> 0.124 ms, best of 60)."""
    for axis in (0, 1):
        if len(points) < 2 or np.diff(np.sort(points[:, axis])).min() > reach * (1 + 1e-6):
            return True
    return False


def thin_ring(points: np.ndarray, sequence: np.ndarray, step: float) -> np.ndarray:
    """Positions in `sequence` kept by thin_curve of points[sequence] (without copying them)."""
    return np.flatnonzero(_thin_ring(points, sequence, step))


@njit(cache=True, nogil=True)
def _thin_ring(points, sequence, step):
    """(n,) bool: the positions thin_ring keeps (np.flatnonzero compiled here cost 0.3 s of the
    first run's compile)."""
    keep = np.zeros(len(sequence), np.bool_)
    if len(sequence) == 0:
        return keep
    keep[0] = True
    last = sequence[0]
    for i in range(1, len(sequence)):
        p = sequence[i]
        if (points[p, 0] - points[last, 0]) ** 2 + (points[p, 1] - points[last, 1]) ** 2 >= (
            step * step
        ):
            keep[i] = True
            last = p
    return keep


FLAT_HULL = 1e-6  # a hull this thin (twice its area over its box's larger side squared) is
# left to Qhull, which decides whether the points are collinear (hull_perimeter)


def hull_perimeter(xy: np.ndarray) -> float:
    """The perimeter of the (n, 2) points' convex hull (0 for collinear points).

    Andrew's monotone chain, compiled: scipy's Qhull took 0.27 ms for a flat ovate's 502-point
    outline (a leaf's outline lies nearly all on its hull), this 0.02 ms, the same perimeter to
    1e-15 of it. Qhull still takes fewer than three points, points that are not finite, and a
    hull all but flat (FLAT_HULL), whose collinear points it finds (0, as before)."""
    xy = kernel_array(xy)
    if len(xy) >= 3 and np.isfinite(xy).all():
        order = np.lexsort((xy[:, 1], xy[:, 0]))
        perimeter, twice_area = _hull(xy, order)
        lo, hi = bounds(xy)
        side = float((hi - lo).max())
        if twice_area > FLAT_HULL * side * side:
            return perimeter
    return _qhull_perimeter(xy)


def _qhull_perimeter(xy: np.ndarray) -> float:
    """hull_perimeter by scipy's Qhull (0 where it finds the points collinear)."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        return float(ConvexHull(xy).area)  # in 2D, "area" is the perimeter
    except (QhullError, ValueError):
        return 0.0


@njit(cache=True, nogil=True)
def _hull(xy, order):
    """The perimeter and twice the area of the convex hull of the (n, 2) points `xy` sorted by
    `order` (x, then y): Andrew's monotone chain, the lower then the upper half."""
    n = len(order)
    hull = np.empty(2 * n, np.int64)
    size = 0
    for sweep in range(2):
        start = size
        for s in range(n):
            i = order[s] if sweep == 0 else order[n - 1 - s]
            while size >= start + 2:
                a, b = hull[size - 2], hull[size - 1]
                cross = (xy[b, 0] - xy[a, 0]) * (xy[i, 1] - xy[a, 1]) - (xy[b, 1] - xy[a, 1]) * (
                    xy[i, 0] - xy[a, 0]
                )
                if cross > 0:
                    break
                size -= 1
            hull[size] = i
            size += 1
        size -= 1  # each half's last point is the other's first
    perimeter, twice_area = 0.0, 0.0
    for s in range(size):
        a, b = hull[s], hull[(s + 1) % size]
        perimeter += np.sqrt((xy[b, 0] - xy[a, 0]) ** 2 + (xy[b, 1] - xy[a, 1]) ** 2)
        twice_area += xy[a, 0] * xy[b, 1] - xy[b, 0] * xy[a, 1]
    return perimeter, twice_area


def thin_outline(polygon: np.ndarray, most: int = MAX_OUTLINE_VERTICES) -> np.ndarray:
    """Indices of the vertices of a polygon with more than `most` of them that are kept, in order.

    Walking round the outline from vertex 0, a vertex is kept once it is at least perimeter / most
    from the last one kept (thin_curve). A dense scan's outline (tens of thousands of points) then
    costs the implicit, the guide and the mesher as much as a few thousand, at a spacing far below
    any grid the app uses, so the dropped points stay within a tiny distance of the kept edges.
    """
    if len(polygon) <= most:
        return np.arange(len(polygon))
    polygon = kernel_array(polygon)
    closed = np.vstack([polygon, polygon[:1]])
    perimeter = float(np.sqrt((np.diff(closed, axis=0) ** 2).sum(axis=1)).sum())
    return thin_curve(polygon, perimeter / most)


def thin_veins(veins: list[np.ndarray], most: int = MAX_OUTLINE_VERTICES) -> list[np.ndarray]:
    """Indices kept of each vein's (m_i, 2) points, when the veins have more than `most` points
    in all: thinned (thin_curve) at their total length / most, as thin_outline does the outline
    (the guide's nearest-vein search costs in proportion to the points)."""
    if sum(len(v) for v in veins) <= most:
        return [np.arange(len(v)) for v in veins]
    total = sum(float(np.sqrt((np.diff(v, axis=0) ** 2).sum(axis=1)).sum()) for v in veins)
    return [thin_curve(v, total / most, keep_end=True) for v in veins]


def thin_curve(points: np.ndarray, step: float, keep_end: bool = False) -> np.ndarray:
    """Indices of the (n, 2) points kept, in order, when each is dropped that lies nearer than
    `step` to the last one kept (the first is always kept, and with `keep_end` the last: an
    open curve's end; unordered points mostly stay)."""
    points = kernel_array(points)
    kept = thin_ring(points, np.arange(len(points)), float(step))
    if keep_end and len(points) and kept[-1] != len(points) - 1:
        kept = np.append(kept, len(points) - 1)
    return kept


def outward_normals(polygon: np.ndarray, smoothing: int = 2) -> np.ndarray:
    """Unit outward normals at the vertices of a counter-clockwise polygon.

    Each normal is perpendicular to the chord between the neighbours `smoothing` steps away, which
    averages out mild noise.
    """
    ahead = np.roll(polygon, -smoothing, axis=0)
    behind = np.roll(polygon, smoothing, axis=0)
    tangent = ahead - behind
    normal = np.column_stack([tangent[:, 1], -tangent[:, 0]])
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    return normal / np.where(length > 0, length, 1.0)


class EdgeBands(NamedTuple):
    """A polygon's edges filed into horizontal bands (edge_bands), for `contains`."""

    y0: float  # the lowest band's bottom
    height: float  # each band's height
    n_bands: int
    tolerance: float  # points this near an edge count as on it
    starts: np.ndarray  # (n_bands + 1,) int64: band b's edges are edges[starts[b]:starts[b + 1]]
    edges: np.ndarray  # (s,) int64 edge indices (edge e runs from vertex e to e + 1)


def edge_bands(polygon: np.ndarray) -> EdgeBands:
    """The (b, 2) polygon's edges filed by horizontal band, about two edges a band: built once
    for a polygon that is tested many times (the pipeline keeps its outline's in its frame
    stage)."""
    polygon = kernel_array(polygon)
    n_bands = max(1, len(polygon) // 2)
    y0, y1 = float(polygon[:, 1].min()), float(polygon[:, 1].max())
    height = max(y1 - y0, 1e-300) / n_bands
    lo, hi = bounds(polygon, lambda p: (p.min(axis=0), p.max(axis=0)))  # np.ptp's, quicker
    tolerance = 1e-12 * float((hi - lo).max())
    starts, edges = _file_edges(polygon, y0, height, n_bands)
    return EdgeBands(y0, height, n_bands, tolerance, starts, edges)


def contains(polygon: np.ndarray, xy: np.ndarray, bands: EdgeBands | None = None) -> np.ndarray:
    """(n,) bool: which points lie inside the polygon (or on its edge).

    The crossing-number test, compiled: the polygon's edges are filed into horizontal bands
    (`bands`: the polygon's edge_bands when they are known already), so each point only tests
    the few edges of its band.
    """
    polygon = kernel_array(polygon)
    xy = kernel_array(np.atleast_2d(xy)).reshape(-1, 2)
    return _inside(polygon, xy, *(edge_bands(polygon) if bands is None else bands))


@njit(cache=True, nogil=True)
def _band_range(ya: float, yb: float, y0: float, height: float, n_bands: int) -> tuple[int, int]:
    first = min(max(int((min(ya, yb) - y0) / height), 0), n_bands - 1)
    last = min(max(int((max(ya, yb) - y0) / height), 0), n_bands - 1)
    return first, last


@njit(cache=True, nogil=True)
def _file_edges(polygon, y0, height, n_bands):
    """(n_bands + 1,) starts and the edge indices of each band, edges of every band they span."""
    n = len(polygon)
    starts = np.zeros(n_bands + 1, np.int64)
    for e in range(n):
        first, last = _band_range(polygon[e, 1], polygon[(e + 1) % n, 1], y0, height, n_bands)
        for b in range(first + 1, last + 2):  # not a slice: see gmm._m_step
            starts[b] += 1
    for b in range(n_bands):
        starts[b + 1] += starts[b]
    edges = np.empty(starts[-1], np.int64)
    fill = np.empty(n_bands, np.int64)
    for b in range(n_bands):  # not a slice's copy: see gmm._m_step
        fill[b] = starts[b]
    for e in range(n):
        first, last = _band_range(polygon[e, 1], polygon[(e + 1) % n, 1], y0, height, n_bands)
        for b in range(first, last + 1):
            edges[fill[b]] = e
            fill[b] += 1
    return starts, edges


@njit(cache=True, nogil=True)
def _inside(polygon, xy, y0, height, n_bands, tolerance, starts, edges):
    n = len(polygon)
    out = np.zeros(len(xy), np.bool_)
    for i in range(len(xy)):
        px, py = xy[i, 0], xy[i, 1]
        if py < y0 - tolerance or py > y0 + height * n_bands + tolerance:
            continue
        band = min(max(int((py - y0) / height), 0), n_bands - 1)
        inside = False
        for s in range(starts[band], starts[band + 1]):
            e = edges[s]
            ax, ay = polygon[e, 0], polygon[e, 1]
            bx, by = polygon[(e + 1) % n, 0], polygon[(e + 1) % n, 1]
            # on the edge itself: covered
            ex, ey = bx - ax, by - ay
            length2 = ex * ex + ey * ey
            t = ((px - ax) * ex + (py - ay) * ey) / length2 if length2 > 0 else 0.0
            t = min(max(t, 0.0), 1.0)
            if (ax + t * ex - px) ** 2 + (ay + t * ey - py) ** 2 <= tolerance * tolerance:
                inside = True
                break
            if (ay > py) != (by > py) and px < ax + (py - ay) * ex / ey:
                inside = not inside
        out[i] = inside
    return out


def ring_crossings(ring: np.ndarray) -> np.ndarray:
    """Where a closed polyline of (n, 2) points crosses itself: (c, 2) points, empty if never.

    Segments that are not neighbours along the ring and meet are crossings (an STRtree finds
    the candidate pairs, so a long ring costs little more than a short one). A ring that GEOS
    finds simple has none: one call, 0.3 ms where the pairs took 25 ms for 2,000 points (the app
    asks on every sketch edit). A point given twice in a row (a closed polyline's first point
    again at its end) is a step of length 0, not a crossing: dropped.
    """
    ring = np.asarray(ring, dtype=float)
    ring = ring[np.any(ring != np.roll(ring, 1, axis=0), axis=1)]  # NaN != NaN: kept
    n = len(ring)
    if n < 4:
        return np.zeros((0, 2))
    ends = np.roll(ring, -1, axis=0)
    if np.all(np.isfinite(ring)) and shapely.is_simple(shapely.LinearRing(ring)):
        return np.zeros((0, 2))
    segments = shapely.linestrings(np.stack([ring, ends], axis=1))
    left, right = shapely.STRtree(segments).query(segments, predicate="intersects")
    apart = (right > left) & ((right - left) % n > 1) & ((left - right) % n > 1)
    if not np.any(apart):
        return np.zeros((0, 2))
    meet = shapely.intersection(segments[left[apart]], segments[right[apart]])
    points = shapely.get_coordinates(shapely.centroid(meet))
    return points.reshape(-1, 2)
