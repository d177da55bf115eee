"""Is the input plausibly one leaf? Tests that turn a silent wrong answer into a message.

`check_leaf_like` looks at a scan before `extract`: a leaf is one connected sheet, thin against
its length (a sphere or a 3D blob is not) and locally planar (a surface, not a volume of scattered
points). `leaf_warnings` looks at a Leaf before the reconstruction: veins far from the boundary's
plane or outside its extent make a surface of whatever height they say, so that is said.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from leafstudio.core.buckets import median
from leafstudio.core.plane import fixed_sample, principal_spreads
from leafstudio.core.prepare.cover import COVER_SPREAD, FILL_SHARE, surface_cover
from leafstudio.core.prepare.polygon import hull_perimeter
from leafstudio.core.prepare.vein_order import leans_back, midrib_leaning
from leafstudio.errors import LeafError

THIN = 0.6  # thickness (smallest spread) over length (largest), at most (real scans: <= 0.41)
SURFACE_VARIATION = 0.15  # median local λ3 / (λ1 + λ2 + λ3), 16 neighbours (real: <= 0.10)
LOCAL_NEIGHBOURS = 16
SAMPLE = 6000  # points tested at most (the real scans hold 2,300-7,300)
LINK = 4.0  # points closer than this many median neighbour spacings belong to one cluster
LARGE_CLUSTER = 0.3  # a cluster with this share of the largest one's points is "large"
LISTED = 4  # the sizes of the largest clusters a refusal names
VEIN_REACH = 1.0  # veins farther than this many leaf lengths from the boundary's plane or extent


def _clusters(points: np.ndarray, tree: cKDTree, nearest: np.ndarray) -> tuple[np.ndarray, ...]:
    """Sizes of the connected groups (largest first), linking points within LINK spacings (the
    median of `nearest`, each point's distance to its nearest other), and (n,) bool: the points
    of the largest."""
    spacing = float(np.median(nearest))
    pairs = tree.query_pairs(LINK * max(spacing, 1e-300), output_type="ndarray")
    n = len(points)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    labels = connected_components(graph, directed=False)[1]
    counts = np.bincount(labels)
    return np.sort(counts)[::-1], labels == np.argmax(counts)


def _surface_variation(points: np.ndarray, index: np.ndarray) -> float:
    """The median share of the smallest local spread: near 0 on a surface, 1/3 in a volume
    (`index`: each sampled point's LOCAL_NEIGHBOURS nearest, itself included)."""
    near = points[index]
    local = near - near.mean(axis=1, keepdims=True)
    eig = np.linalg.eigvalsh(local.transpose(0, 2, 1) @ local)
    total = eig.sum(axis=1)
    ok = total > 0
    return float(np.median(eig[ok, 0] / total[ok])) if ok.any() else 0.0


def _neighbours(points: np.ndarray) -> tuple[cKDTree, np.ndarray, np.ndarray]:
    """One k-d tree for both tests, each point's distance to its nearest other, and the
    LOCAL_NEIGHBOURS nearest of every few points (at most about 2000 sampled). A cloud of under
    4000 points is sampled whole, and its nearest distances are read from that one query."""
    tree = cKDTree(points)
    k = min(LOCAL_NEIGHBOURS, len(points))
    step = max(1, len(points) // 2000)
    dist, index = tree.query(points[::step], k=k)
    nearest = dist[:, 1] if step == 1 else tree.query(points, k=2)[0][:, 1]
    return tree, nearest, index


def leaf_like_problems(points: np.ndarray) -> list[str]:
    """What makes an (n, 3) scan unlike one leaf, one sentence per failed test ([] if none)."""
    points = np.asarray(points, dtype=float)
    # the tests were calibrated on scans of SAMPLE points; denser clouds make the local flatness
    # measure the scanner's noise, and cost seconds
    points = fixed_sample(points, SAMPLE)
    centred = points - points.mean(axis=0)
    scale = float(np.abs(centred).max())
    if not np.isfinite(scale) or scale == 0.0:
        return ["all points are the same point"]
    unit = centred / scale  # the tests are scale-free; this keeps them finite at 1e200
    problems = []
    tree, nearest, index = _neighbours(unit)
    sizes, largest = _clusters(unit, tree, nearest)
    large = int(np.sum(sizes >= LARGE_CLUSTER * sizes[0]))
    if large > 1:
        listed = ", ".join(str(s) for s in sizes[: min(large, LISTED)])
        more = ", ..." if large > LISTED else ""  # the line stays one line (252 sizes were listed)
        problems.append(
            f"not one leaf: {large} large separate clusters of points ({listed}{more} points)"
        )
    # the leaf's thickness, not its strays': 5% of a scan's points thrown up to two lengths off
    # (which the extraction drops) made it "0.67 of its length"
    spreads = principal_spreads(unit[largest])
    if spreads[2] > THIN * spreads[0]:
        problems.append(
            f"not thin: its thickness is {spreads[2] / spreads[0]:.2f} of its length "
            f"(a leaf's is under {THIN})"
        )
    variation = _surface_variation(unit, index)
    if variation > SURFACE_VARIATION:
        problems.append(
            f"not a surface: the points scatter through a volume (local flatness {variation:.2f}, "
            f"a leaf's is under {SURFACE_VARIATION})"
        )
    return problems


def check_leaf_like(points: np.ndarray, force: bool = False) -> list[str]:
    """Raise LeafError naming the failed tests unless `force`; with `force`, return them (for
    warnings)."""
    problems = leaf_like_problems(points)
    if problems and not force:
        raise LeafError(
            f"does not look like one leaf: {'; '.join(problems)} (--force to go on anyway)"
        )
    return problems


def leaf_warnings(leaf) -> list[str]:
    """Warnings about a Leaf whose veins lie far outside the scale of its boundary."""
    boundary = leaf.boundary
    if len(boundary) < 3 or not leaf.veins:
        return []
    centre = boundary.mean(axis=0)
    centred = boundary - centre
    _, _, axes = np.linalg.svd(centred, full_matrices=False)
    normal = axes[2]
    length = float(np.ptp(centred @ axes[0]))
    if not np.isfinite(length) or length <= 0:
        return []
    notes = []
    back, leaning = midrib_leaning(list(leaf.veins))  # as blade_midrib decides it
    if leans_back(back, leaning):
        notes.append(
            f"vein 1, the midrib, seems written from the apex to the base ({back} of its "
            f"{leaning} side veins lean toward its first point): its last point is taken as the "
            "base, for the length, an export's placement and the view"
        )
    for i, vein in enumerate(leaf.veins, start=1):
        offset = vein - centre
        height = float(np.max(np.abs(offset @ normal)))
        if height > VEIN_REACH * length:
            notes.append(
                f"vein {i} lies {height:.4g} from the boundary's plane, more than the leaf's "
                f"length ({length:.4g}); the surface will be that high"
            )
            continue
        # in leaf lengths: the norm's squares overflowed at 1e154 ("reaches inf", issue 24)
        in_plane = (offset - np.outer(offset @ normal, normal)) / length
        reach = float(np.max(np.linalg.norm(in_plane, axis=1))) * length
        if reach > (0.5 + VEIN_REACH) * length:
            notes.append(
                f"vein {i} reaches {reach:.4g} from the leaf's centre, far outside its boundary "
                f"(length {length:.4g})"
            )
    return notes


def boundary_cover(boundary: np.ndarray, loop: Loop | None = None) -> tuple[float, float]:
    """cover.surface_cover of (n, 3) boundary points: how much they cover a surface, and, where
    too sparse for that, the share of them surrounded; (0, 0) for a traced outline (is_outline,
    `loop` its read_loop when the caller has it: the cover's search skipped). Over COVER_SPREAD
    or FILL_SHARE the points are a scan's (the app opens such a point list as one:
    sources/scan.looks_like_scan)."""
    if is_outline(boundary, loop):
        return 0.0, 0.0
    return surface_cover(boundary)


def check_not_a_surface(boundary: np.ndarray, loop: Loop | None = None) -> None:
    """Raise LeafError when the boundary points cover a surface (surface_spread over
    COVER_SPREAD): a scan of the whole leaf given where its boundary belongs, whose outline and
    area would be meaningless and whose surface would be lost; or fill a volume (a 3D blob or a
    sphere's points, too sparse to cover a surface: issue 24, finding 15), by the thinness a
    scan is held to (check_leaf_like); or, too sparse for either, fill an area (a disc of
    points, a hemisphere, a flattened blob: cover.filled_share). `loop`: the boundary's
    read_loop, when the caller has it."""
    spreads = principal_spreads(fixed_sample(boundary, SAMPLE))
    if spreads[2] > THIN * spreads[0]:
        raise LeafError(
            f"the boundary points fill a volume, not a line round a leaf (their thickness is "
            f"{spreads[2] / spreads[0]:.2f} of their length; a leaf's is under {THIN})"
        )
    spread, share = boundary_cover(boundary, loop)
    if spread > COVER_SPREAD:
        raise LeafError(
            f"the boundary points cover a surface, not a line round the leaf (local spread "
            f"{spread:.2f}; an outline's is under {COVER_SPREAD}): this looks like a scan of the "
            "whole leaf; `leafstudio extract SCAN -o LEAF` takes its boundary and veins"
        )
    if share > FILL_SHARE:  # too sparse for the spread: a 400-point blob, a hemisphere
        raise LeafError(
            f"the boundary's points fill an area rather than trace an outline ({share:.0%} of "
            f"them have neighbours on every side; an outline's, under {FILL_SHARE:.0%}): is this "
            "a scan? A boundary is the points round the leaf's edge; `leafstudio extract SCAN "
            "-o LEAF` takes a scan's"
        )


CHECKED_POINTS = 4000  # a longer ordered boundary is checked on every k-th point
CROSSING_SHARE = 0.05  # each side of a crossing encloses at least this share of the area
LOOPS_FROM = 16  # fewer boundary points are taken as one loop
JUMP = 8.0  # a step this many median steps long ends one loop of an ordered boundary
OUTLINE_FROM = 64  # is_outline: a loop of fewer points is looked at as a cloud
OUTLINE_RATIO = 1.75  # ... at most this many times its hull's perimeter long (the gallery's
# forms, teeth and lobes included: 1.52 at most, a lobed reniform; four rows of points traced
# back and forth, the narrowest cloud a closed path can cover, 2)
ZIGZAG = 4.0  # a path this many times its points' hull perimeter zigzags through a cloud: a
# leaf's outline, teeth and lobes included, is under 1.3 of it (gallery forms); a scan's points in
# the scanner's order are 11 to 47 (the real scans)


def _plane_coordinates(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(n, 2) coordinates in the points' best-fit plane, its centre and its two axes."""
    sample = points[:: max(1, len(points) // CHECKED_POINTS)]  # the plane of a few thousand
    centre = sample.mean(axis=0)
    _, _, axes = np.linalg.svd(sample - centre, full_matrices=False)
    # a contiguous (3, 2) matrix: numpy's matmul with the transposed view is 9 times slower
    return (points - centre) @ np.ascontiguousarray(axes[:2].T), centre, axes[:2]


def _loop_ratio(xy: np.ndarray) -> float | None:
    """The length of the closed path through the (n, 2) points in their order over their convex
    hull's perimeter; None unless they are one closed ordered loop (no step longer than JUMP
    median steps: unordered, several loops or an open arc are not)."""
    steps = np.linalg.norm(np.diff(np.vstack([xy, xy[:1]]), axis=0), axis=1)
    typical = median(steps)
    perimeter = hull_perimeter(xy)
    if typical <= 0 or perimeter <= 0 or np.any(steps > JUMP * typical):
        return None
    return float(steps.sum() / perimeter)


class Loop(NamedTuple):
    """A boundary read as one ordered loop: every k-th point (CHECKED_POINTS at most: a lobe
    survives, noise thins) in their best-fit plane, and the closed path's length over its hull's
    perimeter (None: not one closed ordered loop, _loop_ratio). is_outline and
    boundary_crossing both read it; the pipeline reads it once for both (0.4 ms each)."""

    xy: np.ndarray  # (k, 2)
    centre: np.ndarray  # (3,)
    axes: np.ndarray  # (2, 3)
    ratio: float | None


def read_loop(boundary: np.ndarray) -> Loop:
    """The (n, 3) boundary read as one ordered loop (Loop)."""
    points = np.asarray(boundary, dtype=float)
    xy, centre, axes = _plane_coordinates(points[:: max(1, len(points) // CHECKED_POINTS)])
    return Loop(xy, centre, axes, _loop_ratio(xy) if len(xy) >= 3 else None)


def is_outline(boundary: np.ndarray, loop: Loop | None = None) -> bool:
    """Whether the (n, 3) boundary is traced as an outline: at least OUTLINE_FROM points in one
    closed ordered loop at most OUTLINE_RATIO times its hull's perimeter long. Such points cover
    no surface: a closed path through n points spread over an area is about sqrt(n) / 4 times
    its hull's perimeter long, 2 from 64 points (a strip's, its rows over 2: a closed path
    covers an even number of rows, and two are an outline). Checking a form's boundary for a
    surface (surface_cover) was half the frame stage's time (2.3 of 4.9 ms, an ovate). `loop`:
    the boundary's read_loop, when the caller has it."""
    if len(boundary) < OUTLINE_FROM:
        return False
    ratio = (loop or read_loop(boundary)).ratio
    return ratio is not None and ratio <= OUTLINE_RATIO


def boundary_crossing(boundary: np.ndarray, loop: Loop | None = None) -> np.ndarray | None:
    """Where an ordered boundary crosses itself into two or more lobes (a figure eight), as a 3D
    point; None for a simple outline, an unordered cloud, or the small loops of a noisy edge.

    Only a boundary given in order (consecutive points close together, one closed loop) can
    cross itself; an unordered cloud has no crossing to speak of. `loop`: the boundary's
    read_loop, when the caller has it.
    """
    import shapely

    if len(boundary) < 8:
        return None
    xy, centre, axes, ratio = loop or read_loop(boundary)
    if ratio is None or ratio > ZIGZAG:
        return None  # not one closed ordered loop, or a zigzag through a cloud: not an outline
    ring = shapely.LineString(np.vstack([xy, xy[:1]]))
    if ring.is_simple:
        return None
    lobes = list(
        shapely.get_parts(shapely.polygonize(shapely.get_parts(shapely.unary_union(ring))))
    )
    total = sum(lobe.area for lobe in lobes)
    big = sorted(
        (lobe for lobe in lobes if lobe.area >= CROSSING_SHARE * total), key=lambda p: -p.area
    )
    if len(big) < 2:
        return None  # only small loops: a noisy edge, which the outline smooths
    where = big[0].boundary.intersection(big[1].boundary)
    if where.is_empty:
        where = big[0].boundary.intersection(ring)
    x, y = np.asarray(where.representative_point().coords[0])
    return centre + x * axes[0] + y * axes[1]


class BentRefusal(LeafError):
    """A refusal of curves that a blade's own would not earn but a bent leaf's, given without
    its bend, may (its boundary crossing itself on its plane, a vein outside it: check_boundary,
    steps._inside_enough): the pipeline adds that hint when it fits (unfolded.unposed_hint)."""


def check_boundary(
    boundary: np.ndarray,
    scale: float = 1.0,
    shift: np.ndarray | None = None,
    loop: Loop | None = None,
) -> None:
    """Raise LeafError naming where an ordered boundary crosses itself (see boundary_crossing), in
    the user's coordinates `point * scale + shift` (the pipeline runs at unit size)."""
    where = boundary_crossing(boundary, loop)
    if where is not None:
        nearest = int(np.argmin(np.linalg.norm(np.asarray(boundary) - where, axis=1)))
        shown = where * scale + (0.0 if shift is None else shift)
        raise BentRefusal(
            "the boundary crosses itself near ({:.4g}, {:.4g}, {:.4g}), by boundary point {}; "
            "a leaf's outline must not (it would drop a lobe)".format(*shown, nearest + 1)
        )


def boundary_loop_indices(
    boundary: np.ndarray, xy: np.ndarray | None = None
) -> list[np.ndarray] | None:
    """The point indices of each closed loop of a boundary given in order as several loops (an
    outline and its holes, or separate outlines), the largest first; None for one loop or an
    unordered cloud. A loop ends where the next point is far (JUMP median steps) from it. `xy`:
    the boundary on its plane (_plane_coordinates), if the caller has it already."""
    import shapely

    points = np.asarray(boundary, dtype=float)
    if len(points) < LOOPS_FROM:
        return None
    xy = _plane_coordinates(points)[0] if xy is None else xy
    steps = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    typical = median(steps)
    if typical <= 0:
        return None
    cuts = np.flatnonzero(steps > JUMP * typical) + 1
    if len(cuts) == 0 or len(cuts) > 50:
        return None
    loops = np.split(np.arange(len(points)), cuts)
    for loop in loops:
        closing = np.linalg.norm(xy[loop[-1]] - xy[loop[0]])
        if len(loop) < 8 or closing > JUMP * typical:
            return None  # an open piece: not loops
    thin = [loop[:: max(1, len(loop) // CHECKED_POINTS)] for loop in loops]
    path = steps.sum() - steps[cuts - 1].sum()
    if path > ZIGZAG * sum(hull_perimeter(xy[loop]) for loop in thin):
        return None  # zigzags through a cloud, not outlines
    order = np.argsort([-abs(shapely.Polygon(xy[loop]).area) for loop in thin])
    return [loops[i] for i in order]


def keep_outer_loop(boundary: np.ndarray, loop: Loop | None = None) -> tuple[np.ndarray, list[str]]:
    """The boundary's largest loop when it is given as several loops (boundary_loop_indices), with
    a warning naming what was kept and what was dropped; otherwise the boundary as it is.
    `loop`: the boundary's read_loop, when the caller has it (its plane's the same)."""
    import shapely

    points = np.asarray(boundary, dtype=float)
    if len(points) < LOOPS_FROM:
        return boundary, []
    # projected once, for the loops and the holes; onto read_loop's plane (the same sample's),
    # its points themselves when it read them all (0.05 ms of a flat ovate's frame stage)
    if loop is None:
        xy = _plane_coordinates(points)[0]
    elif len(loop.xy) == len(points):
        xy = loop.xy
    else:
        xy = (points - loop.centre) @ np.ascontiguousarray(loop.axes.T)
    loops = boundary_loop_indices(points, xy)
    if loops is None:
        return boundary, []
    outer = shapely.Polygon(xy[loops[0][:: max(1, len(loops[0]) // CHECKED_POINTS)]]).buffer(0)
    holes = [i for i in loops[1:] if outer.contains(shapely.Point(xy[i].mean(axis=0)))]
    others = len(loops) - 1 - len(holes)

    def span(loop: np.ndarray) -> str:
        return f"points {loop[0] + 1}-{loop[-1] + 1}"

    dropped = []
    if holes:
        dropped.append(f"{len(holes)} hole{'s' if len(holes) > 1 else ''} inside it (filled)")
    if others:
        dropped.append(f"{others} separate loop{'s' if others > 1 else ''}")
    note = (
        f"the boundary is {len(loops)} loops; kept the largest ({span(loops[0])}) and dropped "
        f"{' and '.join(dropped)}: {', '.join(span(loop) for loop in loops[1:])}"
    )
    return np.asarray(boundary)[loops[0]], [note]
