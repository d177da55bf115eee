"""The leaf outline: unordered boundary points turned into one simple polygon in the plane.

The MPU implicit needs outward normals, and the conforming mesher and the coverage figures need
the leaf region; both come from this polygon. Ordered input (sketches, sampled curves) is kept in
its order (a dense one thinned to about MAX_OUTLINE_VERTICES); unordered or shuffled input is
ordered by a concave hull of the points.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import shapely
from numba import njit
from shapely.geometry import MultiPoint, Polygon

from leafstudio.core.buckets import bounds, kernel_array, neighbour_distances
from leafstudio.errors import LeafError

_HULL_RATIOS = (0.0, 0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0)
MAX_OUTLINE_VERTICES = 3000  # a denser outline is thinned to about this many (thin_outline)


def distinct_indices(points: np.ndarray, scale: float) -> np.ndarray:
    """Indices of the (n, 2) points left once repeats (within 1e-9 of `scale`) are dropped, in
    order. Column by column: numpy's reductions along axis 0 of an (n, 2) array are slow."""
    if len(points) == 0:
        return np.arange(0)
    columns = [np.round(points[:, i] / (scale * 1e-9)).astype(np.int64) for i in range(2)]
    columns = [c - c.min() for c in columns]
    span_y = int(columns[1].max()) + 1
    if (float(columns[0].max()) + 1) * span_y >= 2.0**62:  # rare: no one integer each
        return np.sort(np.unique(np.column_stack(columns), axis=0, return_index=True)[1])
    keys = columns[0] * span_y + columns[1]
    ordered = np.sort(keys)  # a plain sort: many times faster than a unique with indices
    if np.all(ordered[1:] != ordered[:-1]):
        return np.arange(len(keys))
    order = np.argsort(keys)
    starts = np.flatnonzero(np.r_[True, keys[order[1:]] != keys[order[:-1]]])
    return np.sort(np.minimum.reduceat(order, starts))  # each repeat's first index


SPACING_QUERIES = 2000  # points whose nearest neighbour sets the median spacing, at most


def _spacing(points: np.ndarray) -> float:
    """Median distance from each point to its nearest neighbour (over SPACING_QUERIES points
    evenly through the array, at most: a scale for the tests below, not an exact figure)."""
    every = max(1, len(points) // SPACING_QUERIES)
    return float(np.median(neighbour_distances(points, np.arange(0, len(points), every))))


def _largest_polygon(geom: shapely.Geometry) -> Polygon | None:
    """The largest polygon in `geom`, without holes; None if there is none."""
    polys = [g for g in getattr(geom, "geoms", [geom]) if isinstance(g, Polygon) and g.area > 0]
    if not polys:
        return None
    return Polygon(max(polys, key=lambda g: g.area).exterior)


def _as_ordered(points: np.ndarray, spacing: float) -> Polygon | None:
    """The polygon through the points in their given order, if that order traces the outline.

    More than MAX_OUTLINE_VERTICES of them are thinned first (thin_curve, as thin_outline does),
    so that the validity test checks the outline the pipeline uses, at a fraction of the cost; a
    thinned ring that cuts across a narrow slit is thinned less, down to every point, before
    a self-crossing outline is repaired.
    """
    x, y = points[:, 0], points[:, 1]
    edges = np.hypot(np.diff(x, append=x[0]), np.diff(y, append=y[0]))  # columns: much faster
    if edges.max() > 8 * spacing:
        return None
    step = float(edges.sum()) / MAX_OUTLINE_VERTICES if len(points) > MAX_OUTLINE_VERTICES else 0.0
    finest = float(np.median(edges)) if step > 0 else 0.0  # below this, thinning keeps them all
    while step > 0:
        poly = Polygon(points[thin_curve(points, step)])
        if poly.is_valid:
            return poly
        step = step / 2 if step / 2 > finest else 0.0
    poly = Polygon(points)
    if poly.is_valid:
        return poly
    repaired = _largest_polygon(shapely.make_valid(poly))
    if repaired is not None and repaired.area > 0.9 * abs(shapely.area(poly)):
        return repaired
    return None


def _by_concave_hull(points: np.ndarray, spacing: float) -> Polygon:
    """The tightest concave hull whose outline passes near every point."""
    cloud = MultiPoint(points)
    fallback = None
    for ratio in _HULL_RATIOS:
        poly = _largest_polygon(shapely.concave_hull(cloud, ratio=ratio))
        if poly is None or not poly.is_valid:
            continue
        fallback = fallback or poly
        if shapely.distance(poly.exterior, shapely.points(points)).max() <= 3 * spacing:
            return poly
    if fallback is None:
        raise LeafError("the boundary points do not enclose any area")
    return fallback


def leaf_polygon(points: np.ndarray) -> np.ndarray:
    """Order 2D boundary points into a simple counter-clockwise polygon.

    Parameters
    ----------
    points : (n, 2) float array
        Boundary points in the plane, ordered or not, possibly with duplicates and noise.

    Returns
    -------
    (m, 2) float array
        Polygon vertices (m <= n, each an input point), counter-clockwise, not closed. More
        than MAX_OUTLINE_VERTICES points given in order come back thinned to about that many
        (see thin_outline).
    """
    points = kernel_array(points)
    lo, hi = bounds(points)
    scale = float((hi - lo).max())
    pts = points[distinct_indices(points, scale)]
    if len(pts) < 3:
        raise LeafError(f"the boundary needs at least 3 distinct points, got {len(pts)}")
    spacing = max(_spacing(pts), 1e-12 * scale)
    poly = _as_ordered(pts, spacing) or _by_concave_hull(pts, spacing)
    if poly.area <= 1e-8 * scale**2:
        raise LeafError("the boundary points do not enclose any area")
    poly = shapely.geometry.polygon.orient(poly, sign=1.0)
    return np.asarray(poly.exterior.coords)[:-1]


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
    kept = _thin(kernel_array(points), float(step))
    if keep_end and len(points) and kept[-1] != len(points) - 1:
        kept = np.append(kept, len(points) - 1)
    return kept


@njit(cache=True, nogil=True)
def _thin(points, step):
    keep = np.zeros(len(points), np.bool_)
    if len(points) == 0:
        return np.flatnonzero(keep)
    keep[0] = True
    lx, ly = points[0, 0], points[0, 1]
    for i in range(1, len(points)):
        dx, dy = points[i, 0] - lx, points[i, 1] - ly
        if dx * dx + dy * dy >= step * step:
            keep[i] = True
            lx, ly = points[i, 0], points[i, 1]
    return np.flatnonzero(keep)


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


def contains(polygon: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """(n,) bool: which points lie inside the polygon (or on its edge).

    The crossing-number test, compiled: the polygon's edges are filed into horizontal bands, so
    each point only tests the few edges of its band.
    """
    polygon = kernel_array(polygon)
    xy = kernel_array(np.atleast_2d(xy)).reshape(-1, 2)
    bands = _edge_bands(polygon.tobytes(), len(polygon))
    return _inside(polygon, xy, *bands)


@lru_cache(maxsize=8)
def _edge_bands(key: bytes, n: int) -> tuple[float, float, int, float, np.ndarray, np.ndarray]:
    """The polygon's edges filed by horizontal band (cached: one polygon is tested many times)."""
    polygon = np.frombuffer(key).reshape(n, 2)
    n_bands = max(1, n // 2)
    y0, y1 = float(polygon[:, 1].min()), float(polygon[:, 1].max())
    height = max(y1 - y0, 1e-300) / n_bands
    tolerance = 1e-12 * float(np.ptp(polygon, axis=0).max())
    starts, edges = _file_edges(polygon, y0, height, n_bands)
    return y0, height, n_bands, tolerance, starts, edges


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
        starts[first + 1 : last + 2] += 1
    for b in range(n_bands):
        starts[b + 1] += starts[b]
    edges = np.empty(starts[-1], np.int64)
    fill = starts[:-1].copy()
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
