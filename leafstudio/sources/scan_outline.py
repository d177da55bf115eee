"""A scan's blade outline in its plane (sources/extract.py, step 3): a concave hull of the blade's
points that bridges scanner stripes and nothing wider, opened against a stub of petiole, and
grown to where the blade's edge lies beyond its outermost points; on a flattened blade, kept to
where the sheet was fitted; evenly resampled."""

from __future__ import annotations

import numpy as np
import shapely
from scipy.spatial import Delaunay, cKDTree
from shapely.geometry import MultiPoint, Polygon

from leafstudio.errors import LeafError

OPENING = 0.015  # the outline is opened by this share of the length (drops thin stubs)
NOTCH = 2.0  # the hull is closed by this many point spacings, sqrt(area / points): it dips to
# inner points between the outermost ones (notches up to about 4 spacings wide, the scale it
# bridges: 4 times the points' 95th-percentile gap), not to the blade's edge
EDGE_BEYOND = 0.3  # then grown by this many spacings: the outermost points lie inside the edge.
# bench_scan_truth.py's posed forms, their reconstructed area -3.0 / -2.8 / -2.5 / -2.7% (the
# four noises), grown by 0.38 alone -0.2 / +0.1 / +0.5 / +0.1%, but the surface's vertices then
# stood 0.119% of the extent from the truth (0.089% before) and the truth's 0.100% from them
# (0.125%); closed and grown by 0.3: -0.8 / -0.5 / -0.2 / -0.4%, 0.106% and 0.102%


def outline(xy: np.ndarray, length: float) -> Polygon:
    """A concave hull of the points whose edges bridge gaps of up to four times the scan's typical
    largest point spacing (scanner stripes) and nothing longer, opened by OPENING of the length
    (so that a stub of petiole narrower than twice that is cut off), then closed by NOTCH and
    grown by EDGE_BEYOND of the points' spacing (the hull runs through the outermost points and
    dips between them, inside the blade's edge)."""
    gaps, _ = cKDTree(xy).query(xy, k=2)
    bridge = 4.0 * float(np.percentile(gaps[:, 1], 95))
    simplices = Delaunay(xy).simplices
    edges = np.linalg.norm(xy[simplices] - xy[np.roll(simplices, 1, axis=1)], axis=2)
    lo, hi = float(edges.min()), float(edges.max())
    ratio = float(np.clip((bridge - lo) / max(hi - lo, 1e-300), 0.0, 1.0))
    hull = shapely.concave_hull(MultiPoint(xy), ratio=ratio)
    polys = [g for g in getattr(hull, "geoms", [hull]) if isinstance(g, Polygon) and g.area > 0]
    if not polys:
        raise LeafError("the scan's points do not cover an area")
    hull = max(polys, key=lambda g: g.area)
    radius = OPENING * length
    opened = hull.buffer(-radius, quad_segs=8).buffer(radius, quad_segs=8)
    polys = [g for g in getattr(opened, "geoms", [opened]) if isinstance(g, Polygon)]
    hull = max(polys, key=lambda g: g.area) if polys else hull
    step = np.sqrt(hull.area / len(xy))
    closed = hull.buffer(NOTCH * step, quad_segs=8).buffer(-NOTCH * step, quad_segs=8)
    closed = max(getattr(closed, "geoms", [closed]), key=lambda g: g.area)  # one piece, always
    grown = closed.buffer(EDGE_BEYOND * step, quad_segs=8)
    return shapely.geometry.polygon.orient(Polygon(grown.exterior))


def held_part(polygon: Polygon, means: np.ndarray, reach: float) -> Polygon:
    """The outline's largest part within `reach` of the (m, 2) cube means the sheet was fitted
    to, without holes. The concave hull bridges bays of the flattened blade that hold no scan
    point (a stray point, a scanner's gap); the sheet there is extrapolated, folds, and the mesh
    bent onto it stood out of the scan as a fin (soybean pot1_1's top)."""
    discs = shapely.buffer(shapely.points(means), 2 * reach, quad_segs=4)  # a MultiPoint's
    held = shapely.union_all(discs).buffer(-reach, quad_segs=4)  # buffer: 40 times the time
    part = polygon.intersection(held)  # closed: no slit where a few cube means are missing
    polys = [g for g in getattr(part, "geoms", [part]) if isinstance(g, Polygon) and g.area > 0]
    kept = Polygon(max(polys, key=lambda g: g.area).exterior) if polys else polygon
    if kept.area >= (1 - 1e-9) * polygon.area:  # nothing cut: the outline as it was, from its start
        return polygon
    return shapely.geometry.polygon.orient(kept)


def resample(polygon: Polygon, count: int) -> np.ndarray:
    """(count, 2) points evenly spaced around the polygon's outline, counter-clockwise."""
    ring = polygon.exterior
    steps = np.linspace(0.0, ring.length, count, endpoint=False)
    return shapely.get_coordinates(shapely.line_interpolate_point(ring, steps))
