"""The leaf outline: unordered boundary points turned into one simple polygon in the plane.

The MPU implicit needs outward normals, and the conforming mesher and the coverage figures need
the leaf region; both come from this polygon. Ordered input (sketches, sampled curves) is kept as
given; unordered or shuffled input is ordered by a concave hull of the points.
"""

from __future__ import annotations

import numpy as np
import shapely
from scipy.spatial import cKDTree
from shapely.geometry import MultiPoint, Polygon

from leafstudio.errors import LeafError

_HULL_RATIOS = (0.0, 0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0)


def distinct_indices(points: np.ndarray, scale: float) -> np.ndarray:
    """Indices of the points left once repeats (within 1e-9 of `scale`) are dropped, in order."""
    keys = np.round(points / (scale * 1e-9)).astype(np.int64)
    _, first = np.unique(keys, axis=0, return_index=True)
    return np.sort(first)


def _spacing(points: np.ndarray) -> float:
    """Median distance from each point to its nearest neighbour."""
    dist, _ = cKDTree(points).query(points, k=2)
    return float(np.median(dist[:, 1]))


def _largest_polygon(geom: shapely.Geometry) -> Polygon | None:
    """The largest polygon in `geom`, without holes; None if there is none."""
    polys = [g for g in getattr(geom, "geoms", [geom]) if isinstance(g, Polygon) and g.area > 0]
    if not polys:
        return None
    return Polygon(max(polys, key=lambda g: g.area).exterior)


def _as_ordered(points: np.ndarray, spacing: float) -> Polygon | None:
    """The polygon through the points in their given order, if that order traces the outline."""
    edges = np.linalg.norm(np.diff(np.vstack([points, points[:1]]), axis=0), axis=1)
    if edges.max() > 8 * spacing:
        return None
    poly = Polygon(points)
    if poly.is_valid:
        return poly
    repaired = _largest_polygon(shapely.make_valid(poly))
    if repaired is not None and repaired.area > 0.9 * abs(shapely.area(Polygon(points))):
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
        Polygon vertices (m <= n, each an input point), counter-clockwise, not closed.
    """
    scale = float(np.ptp(points, axis=0).max())
    pts = points[distinct_indices(points, scale)]
    if len(pts) < 3:
        raise LeafError(f"the boundary needs at least 3 distinct points, got {len(pts)}")
    spacing = max(_spacing(pts), 1e-12 * scale)
    poly = _as_ordered(pts, spacing) or _by_concave_hull(pts, spacing)
    if poly.area <= 1e-8 * scale**2:
        raise LeafError("the boundary points do not enclose any area")
    poly = shapely.geometry.polygon.orient(poly, sign=1.0)
    return np.asarray(poly.exterior.coords)[:-1]


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
    """(n,) bool: which points lie inside the polygon (or on its edge)."""
    return shapely.covers(Polygon(polygon), shapely.points(xy))
