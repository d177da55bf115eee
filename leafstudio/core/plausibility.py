"""Is the input plausibly one leaf? Tests that turn a silent wrong answer into a message.

`check_leaf_like` looks at a scan before `extract`: a leaf is one connected sheet, thin against
its length (a sphere or a 3D blob is not) and locally planar (a surface, not a volume of scattered
points). `leaf_warnings` looks at a Leaf before the reconstruction: veins far from the boundary's
plane or outside its extent make a surface of whatever height they say, so that is said.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from leafstudio.core.plane import fixed_sample, principal_extents, principal_spreads
from leafstudio.errors import LeafError

THIN = 0.6  # thickness (smallest spread) over length (largest), at most (real scans: <= 0.41)
SURFACE_VARIATION = 0.15  # median local λ3 / (λ1 + λ2 + λ3), 16 neighbours (real: <= 0.10)
LOCAL_NEIGHBOURS = 16
SAMPLE = 6000  # points tested at most (the real scans hold 2,300-7,300)
LINK = 4.0  # points closer than this many median neighbour spacings belong to one cluster
LARGE_CLUSTER = 0.3  # a cluster with this share of the largest one's points is "large"
VEIN_REACH = 1.0  # veins farther than this many leaf lengths from the boundary's plane or extent


def _clusters(points: np.ndarray, tree: cKDTree, nearest: np.ndarray) -> np.ndarray:
    """Sizes of the connected groups (largest first), linking points within LINK spacings (the
    median of `nearest`, each point's distance to its nearest other)."""
    spacing = float(np.median(nearest))
    pairs = tree.query_pairs(LINK * max(spacing, 1e-300), output_type="ndarray")
    n = len(points)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    labels = connected_components(graph, directed=False)[1]
    return np.sort(np.bincount(labels))[::-1]


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
    sizes = _clusters(unit, tree, nearest)
    large = int(np.sum(sizes >= LARGE_CLUSTER * sizes[0]))
    if large > 1:
        problems.append(
            f"not one leaf: {large} large separate clusters of points "
            f"({', '.join(str(s) for s in sizes[:large])} points)"
        )
    spreads = principal_spreads(unit)
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
    for i, vein in enumerate(leaf.veins, start=1):
        offset = vein - centre
        height = float(np.max(np.abs(offset @ normal)))
        if height > VEIN_REACH * length:
            notes.append(
                f"vein {i} lies {height:.4g} from the boundary's plane, more than the leaf's "
                f"length ({length:.4g}); the surface will be that high"
            )
            continue
        reach = float(np.max(np.linalg.norm(offset - np.outer(offset @ normal, normal), axis=1)))
        if reach > (0.5 + VEIN_REACH) * length:
            notes.append(
                f"vein {i} reaches {reach:.4g} from the leaf's centre, far outside its boundary "
                f"(length {length:.4g})"
            )
    return notes


COVER_REACH = 0.05  # the neighbourhood of a point: this share of the length round it,
COVER_WIDTH = 0.25  # or this share of the width if less, so that a narrow blade's two margins
# (20-30 times longer than wide) never fall in one neighbourhood and look like a surface
COVER_SPREAD = 0.45  # median ratio of the two largest spreads in it: a curve's is near 0 (noise
# of 1% of the length: 0.11, of 2%: 0.35; teeth: at most 0.12), a surface's near 1 (the real
# scans: 0.59 to 0.89)
COVER_CENTRES = 500  # neighbourhoods measured
COVER_POINTS = 5000  # points they are taken from, at most
COVER_LEAST = 8  # a neighbourhood with fewer points is not measured (a sparse outline)
# Two strands: a bent narrow blade's width across is not its straight extent, so its two margins
# can share a neighbourhood (spread 0.46-0.59 at 25-30 times longer than wide, bent 1-3 rad).
# A neighbourhood that reads as a surface is measured again as two strands when its points part
# into two line-like groups with one clear gap between them: a filled patch does not part, and a
# striped scan's lines part into many groups, not two.
STRAND_POINTS = 64  # points of a neighbourhood looked at for strands, at most
STRAND_DIRECTIONS = 8  # directions across it tried first for the gap between two strands
STRAND_SHARE = 0.1  # each strand holds at least this share of those points
STRAND_SECOND = 0.5  # any other gap in between is under this share of the widest (not stripes)
STRAND_APART = 3.0  # the strands' centres lie this many times their summed spreads apart
STRAND_LINE = 0.25  # each strand's own spread ratio is under this (a line, not half a patch)


def _spread_ratios(points: np.ndarray, centres: np.ndarray, reach: float):
    """The points within `reach` of each centre (its neighbourhood): its second spread over its
    largest and its principal axes (ascending), and all their points in units of `reach` round
    their centre, one neighbourhood after the other, where each starts and how many it holds
    (each holds its centre, so none is empty)."""
    pairs = cKDTree(centres).sparse_distance_matrix(
        cKDTree(points), reach, output_type="ndarray"
    )  # one array, several times faster than query_ball_point's lists
    order = np.argsort(pairs["i"], kind="stable")
    owner = pairs["i"][order]
    sizes = np.bincount(owner, minlength=len(centres))
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    local = (points[pairs["j"][order]] - centres[owner]) / reach
    moments = np.column_stack([local, local[:, [0, 0, 0, 1, 1, 2]] * local[:, [0, 1, 2, 1, 2, 2]]])
    sums = np.add.reduceat(moments, starts, axis=0) / sizes[:, None]
    mean = sums[:, :3]
    scatter = np.empty((len(centres), 3, 3))
    for k, (i, j) in enumerate([(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]):
        scatter[:, i, j] = scatter[:, j, i] = sums[:, 3 + k] - mean[:, i] * mean[:, j]
    spread, axes = np.linalg.eigh(scatter)  # ascending
    ratios = spread[:, 1] / np.maximum(spread[:, 2], 1e-300)
    return ratios, axes, local, starts, sizes


def _padded(local: np.ndarray, starts: np.ndarray, sizes: np.ndarray):
    """At most STRAND_POINTS points of each neighbourhood (evenly through its list) as a
    (m, STRAND_POINTS, 3) array, zero past each one's own, and the mask of its own."""
    step = np.maximum(1, -(-sizes // STRAND_POINTS))  # ceil
    taken = -(-sizes // step)
    slot = np.arange(STRAND_POINTS)
    mask = slot[None, :] < taken[:, None]
    index = starts[:, None] + np.where(mask, slot[None, :] * step[:, None], 0)
    return np.where(mask[..., None], local[index], 0.0), mask


def _widest_gap(values: np.ndarray, mask: np.ndarray, least: np.ndarray):
    """The widest gap between the sorted real `values` of each row (..., n) with at least `least`
    of them each side: its width, its middle, and the second widest such gap's width."""
    ranked = np.sort(np.where(mask, values, np.inf), axis=-1)
    with np.errstate(invalid="ignore"):
        gaps = np.diff(ranked, axis=-1)
    j = np.arange(1, gaps.shape[-1] + 1)
    n = mask.sum(axis=-1)[..., None]
    gaps = np.where((j >= least[..., None]) & (j <= n - least[..., None]), gaps, -1.0)
    cut = gaps.argmax(axis=-1)[..., None]
    widest = np.take_along_axis(gaps, cut, -1)[..., 0]
    middle = np.take_along_axis(ranked, cut, -1)[..., 0] + 0.5 * widest
    return widest, middle, np.partition(gaps, -2, axis=-1)[..., -2]


def _moments(points: np.ndarray, inside: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mean and scatter matrix of each row's points (m, k, d) where `inside` (m, k)."""
    weight = inside[..., None]
    mean = (points * weight).sum(axis=1) / np.maximum(inside.sum(axis=1), 1)[:, None]
    centred = (points - mean[:, None]) * weight
    return mean, centred.transpose(0, 2, 1) @ centred


def _two_strands(padded: np.ndarray, mask: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """For each neighbourhood (_padded), the larger spread ratio of its two strands when its
    points part into two line-like strands with one clear gap between them, else inf."""
    least = np.maximum(3, np.ceil(STRAND_SHARE * mask.sum(axis=1))).astype(int)
    plane = padded @ axes[:, :, 1:]  # in the neighbourhood's plane
    # the widest gap over a few directions parts the two sides roughly ...
    angles = np.linspace(0, np.pi, STRAND_DIRECTIONS, endpoint=False)
    across = np.stack([np.cos(angles), np.sin(angles)])
    proj = (plane @ across).transpose(0, 2, 1)  # (m, directions, points)
    shape = proj.shape
    widest, middle, _ = _widest_gap(
        proj, np.broadcast_to(mask[:, None], shape), np.broadcast_to(least[:, None], shape[:2])
    )
    rows, best = np.arange(len(plane)), widest.argmax(axis=1)
    left = mask & (proj[rows, best] < middle[rows, best][:, None])
    # ... and the gap is measured again square to the sides' mean direction
    doubled = np.zeros((len(plane), 2))  # each side's axis as a doubled angle (no sign)
    for side in (left, mask & ~left):
        (xx, xy), (_, yy) = _moments(plane, side)[1].transpose(1, 2, 0)
        doubled += np.column_stack([xx - yy, 2 * xy]) / np.maximum(xx + yy, 1e-300)[:, None]
    along = 0.5 * np.arctan2(doubled[:, 1], doubled[:, 0])
    proj = plane[..., 0] * -np.sin(along)[:, None] + plane[..., 1] * np.cos(along)[:, None]
    widest, middle, second = _widest_gap(proj, mask, least)
    left = mask & (proj < middle[:, None])
    parted = (widest > 0) & (second <= STRAND_SECOND * widest)
    centres, spreads, worst = [], [], np.zeros(len(plane))
    for side in (left, mask & ~left):
        mean, scatter = _moments(proj[..., None], side)
        centres.append(mean[:, 0])
        spreads.append(np.sqrt(scatter[:, 0, 0] / np.maximum(side.sum(axis=1), 1)))
        spread = np.linalg.eigvalsh(_moments(padded, side)[1])  # the strand's own, in 3D
        worst = np.maximum(worst, spread[:, 1] / np.maximum(spread[:, 2], 1e-300))
    parted &= np.abs(centres[1] - centres[0]) >= STRAND_APART * (spreads[0] + spreads[1])
    return np.where(parted & (worst <= STRAND_LINE), worst, np.inf)


def surface_spread(points: np.ndarray) -> float:
    """How much the (n, 3) points cover a surface rather than trace a curve: the median, over
    neighbourhoods of COVER_REACH of the length (COVER_WIDTH of the width if less), of their
    second spread over their largest (0 on a curve, 1 on a surface); 0 when most neighbourhoods
    hold too few points to tell. A neighbourhood holding two line-like strands with one clear gap
    between them (a bent narrow blade's two margins) counts at its strands' spread instead.
    Scale-free and independent of the points' order and of any outline traced through them."""
    points = fixed_sample(np.asarray(points, dtype=float), COVER_POINTS)
    if len(points) == 0 or not np.isfinite(points).all():
        return 0.0
    low, high = points.min(axis=0), points.max(axis=0)
    points = points - (low / 2 + high / 2)
    points /= max(float(np.abs(points).max()), 1e-300)  # finite sums at 1e200 or 1e-200
    length, width = (float(extent) for extent in principal_extents(points)[:2])
    if not np.isfinite(length) or length <= 0:
        return 0.0
    centres = points[:: max(1, len(points) // COVER_CENTRES)]
    reach = min(COVER_REACH * length, COVER_WIDTH * width)
    if reach <= 0:
        return 0.0  # points on one line
    ratios, axes, local, starts, sizes = _spread_ratios(points, centres, reach)
    measured = sizes >= COVER_LEAST
    if measured.sum() < len(centres) / 2:
        return 0.0
    chosen = np.flatnonzero(measured & (ratios > STRAND_LINE))
    if len(chosen):
        padded, mask = _padded(local, starts[chosen], sizes[chosen])
        ratios[chosen] = np.minimum(ratios[chosen], _two_strands(padded, mask, axes[chosen]))
    return float(np.median(ratios[measured]))


def check_not_a_surface(boundary: np.ndarray) -> None:
    """Raise LeafError when the boundary points cover a surface (surface_spread over
    COVER_SPREAD): a scan of the whole leaf given where its boundary belongs, whose outline and
    area would be meaningless and whose surface would be lost."""
    spread = surface_spread(boundary)
    if spread > COVER_SPREAD:
        raise LeafError(
            f"the boundary points cover a surface, not a line round the leaf (local spread "
            f"{spread:.2f}; an outline's is under {COVER_SPREAD}): this looks like a scan of the "
            "whole leaf; `leafstudio extract SCAN -o LEAF` takes its boundary and veins"
        )


CHECKED_POINTS = 4000  # a longer ordered boundary is checked on every k-th point
CROSSING_SHARE = 0.05  # each side of a crossing encloses at least this share of the area
LOOPS_FROM = 16  # fewer boundary points are taken as one loop
JUMP = 8.0  # a step this many median steps long ends one loop of an ordered boundary
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


def hull_perimeter(xy: np.ndarray) -> float:
    """The perimeter of the (n, 2) points' convex hull (0 for collinear points)."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        return float(ConvexHull(xy).area)  # in 2D, "area" is the perimeter
    except (QhullError, ValueError):
        return 0.0


def boundary_crossing(boundary: np.ndarray) -> np.ndarray | None:
    """Where an ordered boundary crosses itself into two or more lobes (a figure eight), as a 3D
    point; None for a simple outline, an unordered cloud, or the small loops of a noisy edge.

    Only a boundary given in order (consecutive points close together, one closed loop) can
    cross itself; an unordered cloud has no crossing to speak of.
    """
    import shapely

    points = np.asarray(boundary, dtype=float)
    if len(points) < 8:
        return None
    points = points[:: max(1, len(points) // CHECKED_POINTS)]  # a lobe survives; noise thins
    xy, centre, axes = _plane_coordinates(points)
    steps = np.linalg.norm(np.diff(np.vstack([xy, xy[:1]]), axis=0), axis=1)
    typical = float(np.median(steps))
    perimeter = hull_perimeter(xy)
    if typical <= 0 or perimeter <= 0 or np.any(steps > JUMP * typical):
        return None  # unordered, or several loops, or an open arc: not one closed ordered loop
    if steps.sum() > ZIGZAG * perimeter:
        return None  # a zigzag through a cloud, not an outline
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


def check_boundary(
    boundary: np.ndarray, scale: float = 1.0, shift: np.ndarray | None = None
) -> None:
    """Raise LeafError naming where an ordered boundary crosses itself (see boundary_crossing), in
    the user's coordinates `point * scale + shift` (the pipeline runs at unit size)."""
    where = boundary_crossing(boundary)
    if where is not None:
        nearest = int(np.argmin(np.linalg.norm(np.asarray(boundary) - where, axis=1)))
        shown = where * scale + (0.0 if shift is None else shift)
        raise LeafError(
            "the boundary crosses itself near ({:.4g}, {:.4g}, {:.4g}), by boundary point {}; "
            "a leaf's outline must not (it would drop a lobe)".format(*shown, nearest + 1)
        )


def boundary_loops(boundary: np.ndarray, xy: np.ndarray | None = None) -> list[np.ndarray] | None:
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
    typical = float(np.median(steps))
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


def keep_outer_loop(boundary: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """The boundary's largest loop when it is given as several loops (see boundary_loops), with
    a warning naming what was kept and what was dropped; otherwise the boundary as it is."""
    import shapely

    points = np.asarray(boundary, dtype=float)
    if len(points) < LOOPS_FROM:
        return boundary, []
    xy = _plane_coordinates(points)[0]  # projected once, for the loops and the holes
    loops = boundary_loops(points, xy)
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
