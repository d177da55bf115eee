"""The leaf outline: unordered boundary points turned into one simple polygon in the plane.

The MPU implicit needs outward normals, and the conforming mesher and the coverage figures need
the leaf region; both come from this polygon (trace_outline). A clean boundary keeps its points
as the outline's vertices: ordered input (sketches, sampled curves) in its order, a dense one
thinned to about MAX_OUTLINE_VERTICES; unordered input in the order a contour round its cells
gives (cloud.py). A noisy boundary, ordered or not, becomes the smooth outline through its points'
mean position. Everything is linear in the number of points but for one sort of them. What the
stages do with the traced polygon (thinning, normals, the inside test) is in polygon.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from scipy.spatial import cKDTree
from shapely.geometry import MultiPoint, Polygon

from leafstudio.core.buckets import (
    bounds,
    kernel_array,
    median,
    near_edges,
    neighbour_distances,
)
from leafstudio.core.jit import njit
from leafstudio.core.prepare.cloud import (
    Cells,
    Noise,
    estimate_noise,
    filled_outline,
    mean_outline,
    order_cells,
    point_order,
)
from leafstudio.core.prepare.plausibility import ZIGZAG
from leafstudio.core.prepare.polygon import (
    MAX_OUTLINE_VERTICES,
    distinct_indices,
    ring_crossings,
    thin_ring,
)
from leafstudio.errors import LeafError

START_TIE = 1e-9  # of the width: x this near the lowest ties for the outline's start (_orientation)
SPARSE_OUTLINE = 48  # an outline of fewer vertices gets points along its edges (_densified)
# points given in order step at most this many median spacings (a longer step: unordered)
ORDERED_STEP_RATIO = 8.0

ORDERED_MEAN_EDGE = 4.0  # given order: mean edge at most this many nearest-neighbour spacings
CLEAN_NOISE = 2e-5  # estimated noise (σ) under this fraction of the size: a clean boundary
RASTER = 512  # the cloud's cells: at least 1/RASTER of its size
HULL_MOST = 5000  # a clean cloud the cells cannot trace is tried by concave hulls up to this
SNAKE = (2.0, 0.25)  # a concave hull this much longer round this share of the area: see _snakes
_HULL_RATIOS = (0.0, 0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0)


SPACING_QUERIES = 2000  # points whose nearest neighbour sets the median spacing, at most
SPACING_POINTS = 20_000  # ... among this many, at most


def _spacing(points: np.ndarray) -> float:
    """Median distance from each point to its nearest neighbour (over SPACING_QUERIES points
    evenly through the array, at most: a scale for the tests below, not an exact figure)."""
    thin = max(1, len(points) // SPACING_POINTS)  # a dense cloud: every thin-th point, whose
    points = points[::thin]  # spacing along a curve is thin times as wide
    every = max(1, len(points) // SPACING_QUERIES)
    queries = np.arange(0, len(points), every)
    return median(neighbour_distances(points, queries)) / thin


def _largest_polygon(geom: shapely.Geometry) -> Polygon | None:
    """The largest polygon in `geom`, without holes; None if there is none."""
    parts = shapely.get_parts(shapely.get_parts(geom))  # a collection may hold multipolygons
    polys = [g for g in parts if isinstance(g, Polygon) and g.area > 0]
    if not polys:
        return None
    return Polygon(max(polys, key=lambda g: g.area).exterior)


@dataclass(frozen=True)
class TracedOutline:
    """The leaf outline traced from boundary points (trace_outline).

    Attributes
    ----------
    polygon : (m, 2) float array
        Counter-clockwise vertices, not closed.
    heights : (m, 2) float array
        The vertices' heights (the input points' own, or their smoothed mean).
    noise : Noise
        The boundary's estimated scatter (cloud.estimate_noise).
    smoothed : bool
        True: the vertices are the points' smoothed mean (a noisy cloud); False: input points.
    """

    polygon: np.ndarray
    heights: np.ndarray
    noise: Noise
    smoothed: bool


def _canonical(points: np.ndarray, sequence: np.ndarray) -> np.ndarray:
    """`sequence` (indices of a closed ring of `points`) counter-clockwise and starting at its
    lowest point by (x, y): the same ring whatever its given start and direction."""
    sequence = np.asarray(sequence, dtype=np.int64)
    twice_area, start = _orientation(kernel_array(points), sequence)
    if twice_area < 0:
        sequence = sequence[::-1]
        start = len(sequence) - 1 - start
    return np.roll(sequence, -start)


@njit(cache=True, nogil=True)
def _orientation(points, sequence):
    """Twice the signed area of the ring points[sequence], and the position in `sequence` of
    its lowest point by x, then y: an x within START_TIE of the ring's width from the lowest
    is a tie. Rounding must not choose between a symmetric outline's two lowest points (issue
    24, finding 19: a cordate leaf moved and scaled started its outline at the other one, the
    boundary was thinned from there, and its area changed by 5e-4)."""
    n = len(sequence)
    area = 0.0
    low, high = np.inf, -np.inf
    for i in range(n):
        a, b = sequence[i], sequence[(i + 1) % n]
        area += points[a, 0] * points[b, 1] - points[b, 0] * points[a, 1]
        low, high = min(low, points[a, 0]), max(high, points[a, 0])
    tie = low + START_TIE * (high - low)
    start = -1
    for i in range(n):
        a = sequence[i]
        if points[a, 0] <= tie and (start < 0 or points[a, 1] < points[sequence[start], 1]):
            start = i
    return area, max(start, 0)


def _ring(points: np.ndarray, sequence: np.ndarray) -> np.ndarray | Polygon | None:
    """The outline through points[sequence] (canonical), thinned to about MAX_OUTLINE_VERTICES
    (polygon.thin_curve): kept indices into `points` if that is a simple polygon, a repaired
    polygon if it crosses itself a little, None if it does not trace an outline.

    The validity test checks the thinned ring (the one the pipeline uses, at a fraction of the
    cost); a thinned ring that cuts across a narrow slit is thinned less, down to every point,
    before a self-crossing outline is repaired.
    """
    points = kernel_array(points)
    sequence = np.asarray(sequence, dtype=np.int64)
    perimeter = _ring_length(points, sequence)
    many = len(sequence) > MAX_OUTLINE_VERTICES
    step = perimeter / MAX_OUTLINE_VERTICES if many else 0.0
    finest = perimeter / len(sequence)  # below this mean edge, thinning keeps about all
    while step > 0:
        kept = sequence[thin_ring(points, sequence, step)]
        if Polygon(points[kept]).is_valid:
            return kept
        step = step / 2 if step / 2 > finest else 0.0
    poly = Polygon(points[sequence])
    if poly.is_valid:
        return sequence
    repaired = _largest_polygon(shapely.make_valid(poly))
    if repaired is not None and repaired.area > 0.9 * abs(shapely.area(poly)):
        return repaired
    return None


@njit(cache=True, nogil=True)
def _ring_length(points, sequence):
    """The length of the closed ring points[sequence]."""
    n = len(sequence)
    total = 0.0
    for i in range(n):
        a, b = sequence[i], sequence[(i + 1) % n]
        total += np.sqrt((points[b, 0] - points[a, 0]) ** 2 + (points[b, 1] - points[a, 1]) ** 2)
    return total


def _given_order(points: np.ndarray, spacing: float) -> np.ndarray | None:
    """The points' indices in their given order, canonical (_canonical), if that order may trace
    the outline: its edges are on average a few spacings long (shuffled points jump across the
    leaf; points at random spacing along the outline pass)."""
    x, y = points[:, 0], points[:, 1]
    edges = np.hypot(np.diff(x, append=x[0]), np.diff(y, append=y[0]))  # columns: much faster
    if edges.mean() > ORDERED_MEAN_EDGE * spacing:
        return None
    return _canonical(points, np.arange(len(points)))


def _cloud_cells(points: np.ndarray, z: np.ndarray, spacing: float) -> Cells | None:
    """cloud.order_cells at a cell of about a spacing (at least 1/RASTER of the cloud's size),
    coarser if the outline does not close at that size; None if it never does."""
    lo, hi = bounds(points)
    size = float((hi - lo).max())
    cell = max(size / RASTER, spacing)
    while cell < size / 4:
        cells = order_cells(points, z, cell)
        if cells is not None:
            return cells
        cell *= 2
    return None


def _exact(
    points: np.ndarray, z: np.ndarray, sequence: np.ndarray, noise: Noise
) -> TracedOutline | None:
    """The outline through the points in `sequence` (input points as vertices, _ring), or None."""
    ring = _ring(points, sequence)
    if ring is None:
        return None
    if isinstance(ring, np.ndarray):
        return TracedOutline(points[ring], z[ring], noise, smoothed=False)
    return _polygon_outline(points, z, ring, noise)  # repaired: some are no input points


def trace_outline(
    points: np.ndarray, z: np.ndarray | None = None, margin: str = "auto"
) -> TracedOutline:
    """The leaf outline from 2D boundary points, ordered or not, clean or noisy, in any number.

    Duplicates are dropped. Points given in an order that traces the outline have their noise
    estimated along it (cloud.estimate_noise); if it is under CLEAN_NOISE of their size they are
    the outline's vertices, in that order (today's fast path). Otherwise the points are placed
    along the outline by a contour round their cells (cloud.order_cells, whatever their order)
    and the noise estimated in that order: a clean boundary keeps its points as the vertices, a
    noisy one becomes the smooth outline through their mean position (cloud.mean_outline), never
    a zig-zag through them. Both orders give the same outline for the same clean points.

    Parameters
    ----------
    points : (n, 2) float array
    z : (n,) float array, optional
        The points' heights above the plane, carried to the outline's vertices (0 if omitted).
    margin : {"auto", "exact", "smooth"}
        Params.margin: "exact" takes every boundary as clean (its points the vertices, where an
        order through them is found), "smooth" every one as noisy; "auto" measures.
    """

    def clean(noise: Noise) -> bool:
        return margin == "exact" or (margin == "auto" and _clean(noise, scale))

    points = kernel_array(points)
    z = np.zeros(len(points)) if z is None else kernel_array(z)
    if len(points) == 0:
        raise LeafError("the boundary needs at least 3 distinct points, got 0")
    lo, hi = bounds(points)
    scale = float((hi - lo).max())
    keep = distinct_indices(points, scale)
    pts, zs = points[keep], z[keep]
    if len(pts) < 3:
        raise LeafError(f"the boundary needs at least 3 distinct points, got {len(pts)}")
    spacing = max(_spacing(pts), 1e-12 * scale)
    given = _given_order(pts, spacing)
    if given is not None:
        noise = estimate_noise(pts, zs, given)
        if clean(noise):
            outline = _exact(pts, zs, given, noise)
            if outline is not None:
                return _checked(outline, scale)
    cells = _cloud_cells(pts, zs, spacing)
    if cells is None and len(pts) <= HULL_MOST:
        hull = _by_concave_hull(pts, spacing)
        if hull is not None:
            return _checked(_polygon_outline(pts, zs, hull), scale)
    if cells is None:  # the points fill the leaf rather than trace its margin
        cell = max(scale / RASTER, spacing)
        polygon, heights = filled_outline(pts, zs, cell)
        return _checked(TracedOutline(polygon, heights, Noise(cell, 0.0), smoothed=True), scale)
    sequence = _canonical(pts, point_order(cells, pts))
    noise = estimate_noise(pts, zs, sequence)
    if clean(noise):
        ring = _ring(pts, sequence)
        if isinstance(ring, np.ndarray):
            return _checked(TracedOutline(pts[ring], zs[ring], noise, smoothed=False), scale)
        # a clean cloud the cells could not trace (walls nearer than its spacing): a small one
        # by the tightest concave hull that passes by every point, else as a noisy one
        hull = _by_concave_hull(pts, spacing) if len(pts) <= HULL_MOST else None
        if hull is not None:
            return _checked(_polygon_outline(pts, zs, hull, noise), scale)
    for wider in (1, 2, 4):  # a fold where the points are sparse: smoothed more
        polygon, heights, noise = mean_outline(cells, len(pts), scale, wider)
        if Polygon(polygon).is_valid:
            break
    if not Polygon(polygon).is_valid:
        poly = _largest_polygon(shapely.make_valid(Polygon(polygon)))
        if poly is None:
            raise LeafError("the boundary points do not enclose any area")
        vertices = np.asarray(poly.exterior.coords)[:-1]
        heights = heights[cKDTree(polygon).query(vertices)[1]]
        polygon = vertices
    return _checked(TracedOutline(polygon, heights, noise, smoothed=True), scale)


def _by_concave_hull(points: np.ndarray, spacing: float) -> Polygon | None:
    """The tightest valid concave hull (shapely) of the points whose outline passes within 3
    spacings of every one (buckets.near_edges, linear); None if none does. A hull that snakes
    through points filling an area (a whole scan given as the boundary: twice the convex hull's
    perimeter round a quarter of its area, SNAKE) traces no margin and is not taken."""
    cloud = MultiPoint(points)
    convex = shapely.convex_hull(cloud)
    for ratio in _HULL_RATIOS:
        poly = _largest_polygon(shapely.concave_hull(cloud, ratio=ratio))
        if poly is None or not poly.is_valid or _snakes(poly, convex):
            continue
        if near_edges(np.asarray(poly.exterior.coords)[:-1], points, 3 * spacing).all():
            return poly
    return None


def _snakes(poly: Polygon, convex: shapely.Geometry) -> bool:
    """True for a polygon that winds through a cloud rather than round it: ZIGZAG times the
    convex hull's perimeter, or SNAKE[0] times it round SNAKE[1] of its area (a leaf's outline,
    teeth, lobes and sinuses included, is under 1.3 times the perimeter round over half the area;
    the real scans' tightest hulls 3 to 12 times round 5% to 35%)."""
    longer, smaller = SNAKE
    if poly.length > ZIGZAG * convex.length:
        return True
    return poly.length > longer * convex.length and poly.area < smaller * convex.area


def _polygon_outline(
    points: np.ndarray, z: np.ndarray, hull: Polygon, noise: Noise | None = None
) -> TracedOutline:
    """The TracedOutline of a polygon whose vertices are (near) input points, such as their concave
    hull: each vertex takes the height of the input point nearest it."""
    vertices = np.asarray(hull.exterior.coords)[:-1]
    heights = z[cKDTree(points).query(vertices)[1]]
    return TracedOutline(vertices, heights, noise or Noise(0.0, 0.0), smoothed=False)


def _clean(noise: Noise, scale: float) -> bool:
    """A boundary whose estimated noise is under CLEAN_NOISE of its size, across and in height."""
    return max(noise.across, noise.height) <= CLEAN_NOISE * scale


def _checked(outline: TracedOutline, scale: float) -> TracedOutline:
    """The outline, if it encloses some area; canonical (counter-clockwise, lowest point first)."""
    polygon = outline.polygon
    x, y = polygon[:, 0], polygon[:, 1]
    if abs(float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))) / 2 <= 1e-8 * scale**2:
        raise LeafError("the boundary points do not enclose any area")
    ring = _canonical(polygon, np.arange(len(polygon)))
    polygon, heights = _densified(polygon[ring], outline.heights[ring])
    return TracedOutline(polygon, heights, outline.noise, outline.smoothed)


def _densified(polygon: np.ndarray, heights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A polygon of few vertices with points added along its edges (heights linear between
    its vertices), about SPARSE_OUTLINE of them in all; a denser one as it is.

    The MPU implicit fits a line to the boundary points near each cell: a triangle or a
    pentagon leaves most cells without points (fuzzing, issue 24: NaN curvatures for 3
    vertices, an outline holding no grid node for 4 to 7). The added points lie on the
    polygon's own edges, so the outline does not change.
    """
    n = len(polygon)
    if n >= SPARSE_OUTLINE:
        return polygon, heights
    ends = np.roll(np.arange(n), -1)
    lengths = np.linalg.norm(polygon[ends] - polygon, axis=1)
    parts = np.maximum(np.ceil(lengths / lengths.sum() * SPARSE_OUTLINE), 1).astype(int)
    t = np.concatenate([np.arange(k) / k for k in parts])
    start = np.repeat(np.arange(n), parts)
    end = ends[start]
    points = polygon[start] + t[:, None] * (polygon[end] - polygon[start])
    return points, heights[start] + t * (heights[end] - heights[start])


def leaf_polygon(points: np.ndarray) -> np.ndarray:
    """Order 2D boundary points into a simple counter-clockwise polygon (trace_outline).

    Parameters
    ----------
    points : (n, 2) float array
        Boundary points in the plane, ordered or not, possibly with duplicates and noise.

    Returns
    -------
    (m, 2) float array
        Polygon vertices, counter-clockwise, not closed: input points for a clean boundary (more
        than MAX_OUTLINE_VERTICES of them come back thinned to about that many, see
        polygon.thin_outline), the smoothed mean outline for a noisy one.
    """
    return trace_outline(points).polygon


def ordered_crossing(xy: np.ndarray) -> np.ndarray | None:
    """(2,) where the (n, 2) plane points, read in their order as an outline, cross themselves,
    or None when they do not or are not in order (a step longer than ORDERED_STEP_RATIO times
    their spacing: a cloud, which the pipeline orders itself). Repeats count once, as the
    outline drops them (at 1e9 from the origin, the nested demo's two tip points 6e-8 apart
    are one, not a crossing): what the app, the commands (workflows.boundary_crossing) and the
    unfolding of a leaf given in 3D (unfold.py) ask alike."""
    xy = xy[distinct_indices(xy, 1.0)]
    if len(xy) < 4:
        return None
    steps = np.linalg.norm(np.diff(np.vstack([xy, xy[:1]]), axis=0), axis=1)
    spacing = float(np.median(cKDTree(xy).query(xy, k=2)[0][:, 1]))  # as trace_outline
    if spacing <= 0 or steps.max() > ORDERED_STEP_RATIO * spacing:
        return None
    found = ring_crossings(xy)
    return found[0] if len(found) else None
