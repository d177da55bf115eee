"""The blade a form's veins grow in (veins.py): the outline in its plane as a polygon, its axis
from base to apex, fast inside and margin-distance tests, and the way back to the boundary's
coordinates with heights above its base surface.
"""

from __future__ import annotations

import numpy as np
import shapely
from scipy.spatial import ConvexHull, QhullError, cKDTree
from shapely.geometry import LineString, Polygon

from leafstudio.core.base import fit_base
from leafstudio.core.plane import fit_frame
from leafstudio.core.prepare.outline import leaf_polygon


def plane_of(boundary: np.ndarray, base):
    """(2D outline, heights or None, frame or None, base in 2D or None); the outline is checked
    already (grow_veins)."""
    points = np.asarray(boundary, dtype=float)
    b = None if base is None else np.asarray(base, dtype=float).ravel()
    if points.shape[1] == 2 or np.all(points[:, 2] == points[0, 2]):
        z0 = None if points.shape[1] == 2 else float(points[0, 2])
        return points[:, :2].copy(), None, z0, None if b is None else b[:2]
    frame = fit_frame(points, np.zeros((0, 3)))
    xy, h = frame.to_plane(points)
    if b is not None:
        if len(b) == 2:  # world x, y: lift to the nearest boundary point's z
            near = np.argmin(np.linalg.norm(points[:, :2] - b, axis=1))
            b = np.array([b[0], b[1], points[near, 2]])
        b = frame.to_plane(b[None])[0][0]
    return xy, h, frame, b


def blade_polygon(xy: np.ndarray) -> Polygon:
    """The outline as a valid shapely polygon (the pipeline's own outline for unordered points)."""
    poly = Polygon(xy)
    if poly.is_valid and poly.area > 0:
        return poly
    ring = leaf_polygon(xy)
    poly = Polygon(ring[0] if isinstance(ring, tuple) else ring)
    if not poly.is_valid:
        poly = shapely.make_valid(poly)
        if not isinstance(poly, Polygon):
            poly = max(getattr(poly, "geoms", [poly]), key=lambda g: g.area)
    return poly


def _ends(poly: Polygon) -> tuple[np.ndarray, np.ndarray]:
    """The two ends of the outline's longest axis (its diameter)."""
    ring = np.asarray(poly.exterior.coords)[:-1]
    try:
        hull = ring[ConvexHull(ring).vertices]
    except QhullError:
        hull = ring
    d = np.linalg.norm(hull[:, None] - hull[None], axis=2)
    i, j = np.unravel_index(np.argmax(d), d.shape)
    return hull[i], hull[j]


def _base_from_apex(poly: Polygon, apex: np.ndarray) -> np.ndarray:
    """Where the midrib meets the blade, seen from the apex: the far crossing of the line from the
    apex through the blade's centroid (a cordate leaf's sinus, not one of its lobes)."""
    c = np.asarray(poly.centroid.coords[0])
    d = c - apex
    d /= np.linalg.norm(d)
    far = apex + d * 4 * np.sqrt(poly.area + poly.length**2)
    cut = poly.exterior.intersection(LineString([apex, far]))
    pts = np.array([g.coords[0] for g in getattr(cut, "geoms", [cut]) if not g.is_empty])
    if len(pts) == 0:
        return c
    return pts[np.argmax((pts - apex) @ d)]


def _width_near(poly: Polygon, end: np.ndarray, other: np.ndarray, share: float) -> float:
    """The blade's width across the axis at `share` of the way from `end` to `other`."""
    d = other - end
    at = end + share * d
    n = np.array([-d[1], d[0]]) / np.linalg.norm(d) * 2 * np.linalg.norm(d)
    return poly.intersection(LineString([at - n, at + n])).length


def find_axis(poly: Polygon, base: np.ndarray | None, near_origin: np.ndarray | None = None):
    """(base, apex) of an outline: the apex is the margin point farthest from a given base; with
    no base, the longest axis's end that lies at the origin (the forms' convention) is the base,
    else its wider end (most leaves are widest below the middle)."""
    if base is not None:
        ring = np.asarray(poly.exterior.coords)[:-1]
        apex = ring[np.argmax(np.linalg.norm(ring - base, axis=1))]
        return np.asarray(base, dtype=float), apex
    e1, e2 = _ends(poly)
    candidates = [(_base_from_apex(poly, e2), e2), (_base_from_apex(poly, e1), e1)]
    length = np.linalg.norm(e2 - e1)
    if near_origin is not None:
        dist = [np.linalg.norm(b - near_origin) for b, _ in candidates]
        if min(dist) < 0.1 * length <= max(dist):
            return candidates[int(np.argmin(dist))]
    wide = [_width_near(poly, b, a, 0.25) for b, a in candidates]
    return candidates[int(np.argmax(wide))]


def cross_sections(poly: Polygon, xs: np.ndarray, mid: np.ndarray) -> np.ndarray:
    """(n, 2) the y-range of the blade's cross-section at each x (the part holding mid[i])."""
    span = 4 * (poly.bounds[3] - poly.bounds[1]) + 1
    lines = shapely.linestrings(
        np.stack(
            [
                np.column_stack([xs, np.full_like(xs, -span)]),
                np.column_stack([xs, np.full_like(xs, span)]),
            ],
            axis=1,
        )
    )
    out = np.zeros((len(xs), 2))
    for i, cut in enumerate(shapely.intersection(getattr(poly, "poly", poly), lines)):
        parts = [
            g for g in getattr(cut, "geoms", [cut]) if isinstance(g, LineString) and not g.is_empty
        ]
        if not parts:
            out[i] = mid[i], mid[i]
            continue
        ranges = [(min(c[1] for c in g.coords), max(c[1] for c in g.coords)) for g in parts]
        gaps = [
            0 if lo <= mid[i] <= hi else min(abs(lo - mid[i]), abs(hi - mid[i]))
            for lo, hi in ranges
        ]
        out[i] = ranges[int(np.argmin(gaps))]
    return out


class Blade:
    """The blade's polygon with a fast inside test and distance to the margin (a k-d tree over
    the margin resampled at a fine step: shapely's exact distance is many times slower)."""

    def __init__(self, poly: Polygon) -> None:
        self.poly = poly
        shapely.prepare(poly)
        ring = poly.exterior
        step = ring.length / max(int(ring.length / 0.002), 64)
        dense = shapely.get_coordinates(ring.segmentize(step))
        self.tree = cKDTree(dense)
        self.spacing = step  # no margin point farther than half this from a point of the tree
        self.area = poly.area

    def __getattr__(self, name: str):
        return getattr(self.poly, name)

    def gap(self, pts: np.ndarray) -> np.ndarray:
        """(n,) distance from each point to the margin."""
        return self.tree.query(np.asarray(pts, dtype=float))[0]

    def radius_below(self, across: int = 9) -> float:
        """A radius the blade's inscribed circle has at least: the largest distance to the
        margin from the points of an `across` x `across` grid over its box that lie inside, less
        half the tree's spacing (`gap` is never more than that over the true distance); 0 for a
        blade with holes, whose margin the tree does not hold."""
        if self.poly.interiors:
            return 0.0
        x0, y0, x1, y1 = self.poly.bounds
        gx, gy = np.meshgrid(np.linspace(x0, x1, across), np.linspace(y0, y1, across))
        points = np.column_stack([gx.ravel(), gy.ravel()])
        points = points[shapely.contains_xy(self.poly, points[:, 0], points[:, 1])]
        return float(self.gap(points).max()) - self.spacing / 2 if len(points) else 0.0

    def inside(self, pts: np.ndarray, margin: float = 0.0) -> np.ndarray:
        pts = np.asarray(pts, dtype=float)
        inside = shapely.contains_xy(self.poly, pts[:, 0], pts[:, 1])
        if margin > 0:  # no margin point within `margin` (bounded: a k-d tree query from deep
            # inside a round blade otherwise visits every margin point)
            bound = np.nextafter(margin, np.inf)
            inside &= self.tree.query(pts, distance_upper_bound=bound)[0] > margin
        return inside


def lifter(xy, heights, frame, poly):
    """Maps plane points and heights above b(x) to the boundary's coordinates."""
    if heights is None:
        z0 = frame if isinstance(frame, float) else 0.0
        return lambda pts, relief: np.column_stack([pts, relief + z0])
    ring = np.asarray(poly.exterior.coords)[:-1]
    near = cKDTree(xy).query(ring)[1]
    base = fit_base(ring, heights[near], float(np.sqrt(poly.area) * 2))
    if base is None:
        return lambda pts, relief: frame.to_world(pts, relief)
    return lambda pts, relief: frame.to_world(pts, relief + base(pts))
