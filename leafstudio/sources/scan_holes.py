"""Real holes in a scan's blade (issue 21): a part of the flattened blade, inside its outline,
that no scan point comes near, kept open in the mesh.

The outline is one ring (model.Leaf), so the mesh spans whatever lies inside it; sugar beet
pot1_7 has a hole torn in its blade, and its surface spanned it (1.97% of the mesh's area
farther than 3% of the length from every scan point). A hole is where a disc of HOLE point gaps'
radius (the gap: the 95th percentile of the points' nearest-neighbour distances) fits between the
points, away from the outline (a bay of the margin is the outline's business); it is the union of
all such empty discs, so that its edge runs through the points around it. Scanner stripes leave
empty discs of at most two gaps' radius (the outline bridges gaps of four), so they are no hole:
the eight shared scans hold one hole at HOLE 3 to 6 (pot1_7's), and 2 to 16 at HOLE 2.
"""

from __future__ import annotations

import numpy as np
import shapely
from scipy.spatial import cKDTree
from shapely.geometry import Polygon

HOLE = 4.0  # the smallest hole's radius, in point gaps
ROUND = 8  # segments of a quarter circle in the discs


def holes(region: Polygon, tree: cKDTree, gap: float) -> list[np.ndarray]:
    """(k, 2) rings of the holes among the blade points of `tree` within their outline `region`.

    Parameters
    ----------
    region : Polygon
        The blade's outline (a little widened), in the points' plane.
    tree : cKDTree
        Over the blade's (n, 2) points in that plane (extract.py's, built once for the veins too).
    gap : float
        The 95th percentile of the points' nearest-neighbour distances.

    Returns
    -------
    list of (k, 2) float arrays
        Each hole's outline, closed (its first point repeated last); none for a blade without one.
    """
    xy = tree.data
    if len(xy) < 3:
        return []
    radius = HOLE * gap
    if not radius > 0 or not _room(region, tree, radius):
        return []
    kept = _near_gaps(region, tree, radius)
    if not kept.any():
        return []
    near = shapely.union_all(shapely.buffer(shapely.points(xy[kept]), radius, quad_segs=ROUND))
    far = region.difference(near)  # the centres of the empty discs, and gaps the rest would fill
    found = []
    for piece in getattr(far, "geoms", [far]):
        if not isinstance(piece, Polygon) or piece.area == 0 or piece.intersects(region.exterior):
            continue
        if _covered(piece.representative_point(), tree, radius):
            continue  # in a disc left out of the union: no empty disc's centre
        hole = piece.buffer(radius, quad_segs=ROUND).intersection(region)
        parts = [g for g in getattr(hole, "geoms", [hole]) if isinstance(g, Polygon)]
        found += [np.asarray(g.exterior.coords) for g in parts if g.area > 0]
    return found


def _near_gaps(region: Polygon, tree: cKDTree, radius: float) -> np.ndarray:
    """(n,) bool: the points of `tree` whose discs may bound an empty disc's centre, those within
    `radius` and a grid node's reach of a node of a grid of half `radius` (over the region's
    box and a step beyond) that is at least the discs' inradius less that reach from every point.

    A centre c of an empty disc lies outside every point's disc polygon, which holds the circle
    of its inradius, so c is farther than the inradius from every point, and its nearest node
    (within the reach, half a cell's diagonal) farther than the inradius less the reach. A disc
    that comes within the reach of c then belongs to a point within `radius` and twice the reach
    of that node: near each centre, and along the edges of each piece of them, the union of the
    kept discs is the union of all (merging all 40,000 of a synthetic scan's took 2-3 s, most of
    its extraction). A piece of the region outside the kept discs is then either a piece of
    centres, whole, or lies inside discs left out (`_covered`)."""
    step = radius / 2
    reach = step / np.sqrt(2)
    inradius = radius * np.cos(np.pi / (4 * ROUND))  # the disc polygons have 4 ROUND sides
    nodes = _grid(region, step, pad=step)
    clear = tree.query(nodes, distance_upper_bound=inradius)[0]
    centres = nodes[clear >= inradius - reach]
    if not len(centres):
        return np.zeros(len(tree.data), dtype=bool)
    near = cKDTree(centres).query(tree.data, distance_upper_bound=radius + 2 * reach)[0]
    return np.isfinite(near)


def _covered(point: shapely.Point, tree: cKDTree, radius: float) -> bool:
    """Whether `point` lies inside the disc polygon of a point of `tree` (those within
    `radius`)."""
    close = tree.query_ball_point(np.asarray(point.coords[0]), radius)
    if not close:
        return False
    discs = shapely.buffer(shapely.points(tree.data[close]), radius, quad_segs=ROUND)
    return bool(np.any(shapely.contains(discs, point)))


def _room(region: Polygon, tree: cKDTree, radius: float) -> bool:
    """Whether an empty disc of `radius` may fit among the points of `tree` within `region`: a
    grid of half its radius has a node within `radius` / (2 sqrt 2) of the disc's centre, that
    far at least from every point inside the disc. A quick no for a blade without a hole (the
    union of the points' discs cost 0.1 s a scan)."""
    step = radius / 2
    nodes = _grid(region, step)
    nodes = nodes[shapely.contains_xy(region, nodes[:, 0], nodes[:, 1])]
    clear = tree.query(nodes, distance_upper_bound=radius)[0]
    return bool(np.any(clear >= radius - step / np.sqrt(2)))


def _grid(region: Polygon, step: float, pad: float = 0.0) -> np.ndarray:
    """(n, 2) nodes `step` apart over the region's box, widened by `pad` on every side."""
    lo, hi = np.asarray(region.bounds[:2]) - pad, np.asarray(region.bounds[2:]) + pad
    u, v = (np.arange(lo[k], hi[k] + step, step) for k in (0, 1))
    return np.stack(np.meshgrid(u, v), -1).reshape(-1, 2)
