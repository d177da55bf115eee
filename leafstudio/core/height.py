"""Step 3 (section 3.3): the height guide p(x) of section 3.3 (eqs. 4-5), the probability map on the
grid.

Between the margin and a vein (eq. 4), p rises linearly from 0 at the nearest boundary point b to
the vein's height h_v at its projection v':

    p(x) = h_v |b − x| / |b − v'|

When the two nearest height constraints are two veins rather than a vein and the margin (parallel
veins), eq. 5 applies. Its printed form is garbled; we use (docs/architecture.md, the surface),

    p(x) = h_v (1 − |v' − x| / (2 |v' − v''|))

with |v' − v''| measured through x (|v' − x| + |x − v''|, equal to it for x between two parallel
veins and never zero where veins meet), so p dips gently between veins, to 3/4 of h_v midway.
Ties among nearest points are averaged, as the paper says. Heights are signed: a vein below the
boundary's plane pulls p below zero.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from leafstudio.core.buckets import Buckets, bounds, bucket_points, kernel_array
from leafstudio.core.jit import njit
from leafstudio.core.prepare.polygon import thin_curve

TIE = 1e-9  # relative distance under which nearest points count as tied
QUERIES_PER_BUCKET = 32  # query points share one candidate list per bucket of about this many
BLOCK = 4  # buckets per side of a block, whose candidate list the buckets then filter


def query_buckets(xy: np.ndarray) -> Buckets:
    """The (n >= 1, 2) queries' buckets for nearest_in_groups, about QUERIES_PER_BUCKET each."""
    xy = kernel_array(xy)
    lo, hi = bounds(xy)  # np.ptp(axis=0) on (n, 2) is many times slower
    extent = hi - lo
    size = max(float(np.sqrt(extent[0] * extent[1] * QUERIES_PER_BUCKET / len(xy))), 1e-12)
    return bucket_points(xy, size=max(size, float(extent.max()) / 1024))


def nearest_in_groups(
    xy: np.ndarray,
    points: np.ndarray,
    group: np.ndarray,
    values: np.ndarray,
    buckets: Buckets | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """For each query, the nearest group of points and the next nearest other group.

    Parameters
    ----------
    xy : (n, 2) float array
        Query points.
    points : (m, 2) float array
        Data points, m >= 1.
    group : (m,) int array
        Group of each point (0, 1, ...): a vein's index, or all 0 for the boundary.
    values : (m,) float array
        A value carried by each point (a vein point's height).
    buckets : Buckets, optional
        query_buckets(xy), when the caller has them (height_guide: for both its searches).

    Returns
    -------
    dist : (n,) float array
        Distance to the nearest point.
    position : (n, 2) float array
        Mean position of the nearest point and the points tied with it in its group.
    value : (n,) float array
        Mean value of those tied points.
    second : (n,) float array
        Distance to the nearest point of any other group; inf with a single group.
    """
    xy = kernel_array(xy)
    n = len(xy)
    dist, second, value = np.empty(n), np.empty(n), np.empty(n)
    position = np.empty((n, 2))
    if n == 0:
        return dist, position, value, second
    b = query_buckets(xy) if buckets is None else buckets
    _nearest_groups(
        xy, kernel_array(points), np.asarray(group, dtype=np.int64),
        np.asarray(values, dtype=float), int(np.max(group)) + 1, b, dist, position, value,
        second,
    )  # fmt: skip
    return dist, position, value, second


@njit(cache=True, nogil=True)
def _select(points, group, n_groups, pool, n_pool, x0, y0, x1, y1, bound, near, out):
    """Fill `out` with the points of pool[:n_pool] that can be the nearest point of one of the
    two nearest groups of some query in the box [x0, x1] x [y0, y1]; return their count.

    bound[g] is the farthest any query in the box can be from a pool point of group g, so the
    second nearest group of every query lies within the second smallest bound (cut); a point
    nearer to the box than neither its group's bound nor the cut is never needed."""
    for g in range(n_groups):  # loops, not bound[:] = ... or a 3-argument max: each compiles
        bound[g] = np.inf  # code of its own (seconds of the first run's compile, in all)
    for s in range(n_pool):
        j = pool[s]
        px, py = points[j, 0], points[j, 1]
        ex = max(max(x0 - px, 0.0), px - x1)
        ey = max(max(y0 - py, 0.0), py - y1)
        near[s] = ex * ex + ey * ey
        fx = max(abs(px - x0), abs(px - x1))
        fy = max(abs(py - y0), abs(py - y1))
        bound[group[j]] = min(bound[group[j]], fx * fx + fy * fy)
    least = second = np.inf  # the cut: the second smallest bound (the smallest for one group)
    for g in range(n_groups):
        if bound[g] < least:
            least, second = bound[g], least
        elif bound[g] < second:
            second = bound[g]
    cut = least if n_groups == 1 else second
    count = 0
    for s in range(n_pool):
        j = pool[s]
        limit = min(bound[group[j]], cut)
        if near[s] <= (np.sqrt(limit) * (1 + 1e-6) + 1e-12) ** 2:
            out[count] = j
            count += 1
    return count


@njit(cache=True, nogil=True)
def _nearest_groups(xy, points, group, values, n_groups, b, dist, pos, value, second):
    """Per block of BLOCK x BLOCK query buckets a candidate list from all points, per bucket one
    from its block's list (see _select: both exact), then each query scans its bucket's list."""
    lo, size, nx, ny, starts, order = b
    m = len(points)
    bound = np.empty(n_groups)
    near = np.empty(m)
    everyone = np.empty(m, np.int64)
    for j in range(m):
        everyone[j] = j
    pool = np.empty(m, np.int64)
    candidates = np.empty(m, np.int64)
    cx, cy = np.empty(m), np.empty(m)  # the candidates' x and y, contiguous for _scan's loops
    close = np.empty(m, np.int64)  # those within a query's tie (_scan)
    best = np.empty(n_groups)
    for block_y in range(0, ny, BLOCK):
        for block_x in range(0, nx, BLOCK):
            last_y, last_x = min(block_y + BLOCK, ny), min(block_x + BLOCK, nx)
            if starts[(last_y - 1) * nx + last_x] == starts[block_y * nx + block_x]:
                continue  # buckets are numbered row by row: no query in the block's rows span
            n_pool = _select(
                points, group, n_groups, everyone, m,
                lo[0] + block_x * size, lo[1] + block_y * size,
                lo[0] + last_x * size, lo[1] + last_y * size,
                bound, near, pool,
            )  # fmt: skip
            for by in range(block_y, last_y):
                for bx in range(block_x, last_x):
                    k = by * nx + bx
                    if starts[k] == starts[k + 1]:
                        continue
                    x0, y0 = lo[0] + bx * size, lo[1] + by * size
                    count = _select(
                        points, group, n_groups, pool, n_pool, x0, y0, x0 + size, y0 + size,
                        bound, near, candidates,
                    )  # fmt: skip
                    _scan(
                        xy, points, group, values, n_groups, starts[k], starts[k + 1], order,
                        candidates, count, best, dist, pos, value, second, cx, cy, close,
                    )  # fmt: skip


@njit(cache=True, nogil=True)
def _scan(
    xy, points, group, values, n_groups, first_q, end_q, order, candidates, count, best, dist,
    pos, value, second, cx, cy, near,
):  # fmt: skip
    """Nearest group, tie-averaged nearest point and value, and next group's distance, for the
    queries order[first_q:end_q] among the candidates, whose x and y are copied to `cx` and
    `cy` first: read from there, and with one group (the boundary) without its group's
    look-up, the boundary's search at a flat ovate's 6895 nodes at grid 128 took 1.33 ms
    instead of 2.6 (best of 50; the same figures to the bit). The boundary's nearest by four
    running minima (_nearest_square), and the candidates within the tie picked without a
    branch (`near`, in candidate order, so the tied sums add in the same order) before their
    group is asked: 1.61 -> 1.02 ms, the veins' search 0.78 -> 0.71 (best of 40; the same
    figures to the bit)."""
    for c in range(count):
        j = candidates[c]
        cx[c], cy[c] = points[j, 0], points[j, 1]
    for s in range(first_q, end_q):
        i = order[s]
        qx, qy = xy[i, 0], xy[i, 1]
        if n_groups == 1:
            best[0] = _nearest_square(cx, cy, count, qx, qy)
        else:
            for g in range(n_groups):
                best[g] = np.inf
            for c in range(count):
                j = candidates[c]
                d2 = (cx[c] - qx) ** 2 + (cy[c] - qy) ** 2
                best[group[j]] = min(best[group[j]], d2)
        first = 0
        for g in range(1, n_groups):
            if best[g] < best[first]:
                first = g
        d1 = np.sqrt(best[first])
        d_other = np.inf
        for g in range(n_groups):
            if g != first:
                d_other = min(d_other, best[g])
        tie = (d1 * (1 + TIE) + 1e-15) ** 2
        close = 0  # the candidates within the tie, found without a branch
        for c in range(count):
            near[close] = c
            close += (cx[c] - qx) ** 2 + (cy[c] - qy) ** 2 <= tie
        tied, sx, sy, sv = 0, 0.0, 0.0, 0.0
        for t in range(close):
            c = near[t]
            j = candidates[c]
            if group[j] == first:
                tied += 1
                sx += cx[c]
                sy += cy[c]
                sv += values[j]
        dist[i], second[i] = d1, np.sqrt(d_other)
        pos[i, 0], pos[i, 1], value[i] = sx / tied, sy / tied, sv / tied


@njit(cache=True, nogil=True)
def _nearest_square(cx, cy, count, qx, qy):
    """The least (cx[c] - qx)² + (cy[c] - qy)² over c < count: four running minima, each over
    every fourth candidate, so that each waits for no other (one took a min's latency per
    candidate); a minimum is exact in any order, so the same figure to the bit."""
    m0 = m1 = m2 = m3 = np.inf
    c = 0
    while c + 4 <= count:
        m0 = min(m0, (cx[c] - qx) ** 2 + (cy[c] - qy) ** 2)
        m1 = min(m1, (cx[c + 1] - qx) ** 2 + (cy[c + 1] - qy) ** 2)
        m2 = min(m2, (cx[c + 2] - qx) ** 2 + (cy[c + 2] - qy) ** 2)
        m3 = min(m3, (cx[c + 3] - qx) ** 2 + (cy[c + 3] - qy) ** 2)
        c += 4
    while c < count:
        m0 = min(m0, (cx[c] - qx) ** 2 + (cy[c] - qy) ** 2)
        c += 1
    return min(min(m0, m1), min(m2, m3))


def height_guide(
    xy: np.ndarray,
    boundary: np.ndarray,
    veins: list[np.ndarray],
    heights: list[np.ndarray],
    step: float = 0.0,
) -> np.ndarray:
    """The guide p at points inside the leaf.

    Parameters
    ----------
    xy : (n, 2) float array
        Query points (grid nodes with g >= 0).
    boundary : (b, 2) float array
        Boundary points in the plane.
    veins : list of (m_i, 2) float arrays
        Vein points projected onto the plane (v'), one array per vein.
    heights : list of (m_i,) float arrays
        Signed heights h_v of the vein points (eq. 3).
    step : float, optional
        Points nearer than `step` to the last one kept along the boundary or a vein are left
        out (thin_curve). The pipeline passes half its grid step: p is sampled on the grid, a
        polyline that much denser moves the nearest point by a fraction of its spacing, and the
        search costs in proportion to the points (a 50,000-point scan's, several times more).

    Returns
    -------
    (n,) float array
        p(x); all zeros when there are no veins (a flat leaf).
    """
    xy = kernel_array(xy)
    if not veins:
        return np.zeros(len(xy))
    if step > 0:
        boundary = boundary[thin_curve(boundary, step)]
        kept = [thin_curve(vein, step, keep_end=True) for vein in veins]
        veins = [vein[keep] for vein, keep in zip(veins, kept, strict=True)]
        heights = [h[keep] for h, keep in zip(heights, kept, strict=True)]
    zeros = np.zeros(len(boundary))
    # the queries bucketed once for both searches (0.10 ms of a flat ovate's guide at grid 128)
    buckets = query_buckets(xy) if len(xy) else None
    d_b, b, _, _ = nearest_in_groups(xy, boundary, zeros.astype(np.int64), zeros, buckets)
    ids = np.repeat(np.arange(len(veins)), [len(v) for v in veins])
    d_v, v_pos, h_v, d_v2 = nearest_in_groups(
        xy, np.vstack(veins), ids, np.concatenate(heights), buckets
    )

    # eq. 4: between the margin and the nearest vein
    reach = np.hypot(b[:, 0] - v_pos[:, 0], b[:, 1] - v_pos[:, 1])
    _average_tied_reach(reach, xy, boundary, np.vstack(veins), b, d_b, v_pos, d_v)
    p = h_v * np.clip(d_b / np.maximum(reach, 1e-300), 0.0, 1.0)
    # eq. 5: between two veins, when both are nearer than the margin (d_v2 is inf for one vein)
    between = d_v2 < d_b
    ratio = d_v / np.maximum(2 * (d_v + d_v2), 1e-300)
    return np.where(between, h_v * (1 - ratio), p)


def _nearer_than(xy: np.ndarray, position: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """(n,) bool: |x − position| < dist (1 − 1e-7), i.e. a tie-averaged position. (Not compiled:
    0.03 ms at grid 128, 1 ms at 512, where it cost 0.3 s of the first run's compile.)"""
    dx, dy = xy[:, 0] - position[:, 0], xy[:, 1] - position[:, 1]
    return np.sqrt(dx * dx + dy * dy) < dist * (1 - 1e-7)


def _average_tied_reach(
    reach: np.ndarray,
    xy: np.ndarray,
    boundary: np.ndarray,
    vein_points: np.ndarray,
    b: np.ndarray,
    d_b: np.ndarray,
    v_pos: np.ndarray,
    d_v: np.ndarray,
) -> None:
    """Where several boundary or vein points are nearest at once, set |b − v'| to the mean over
    all their pairs, as the paper says (in place; rare, so done apart from the compiled search).

    The mean of several points at the same distance lies strictly nearer than that distance, so a
    tie shows as a mean position closer to the query than its nearest distance.
    """
    tied = _nearer_than(xy, b, d_b) | _nearer_than(xy, v_pos, d_v)
    if not tied.any():
        return
    b_tree, v_tree = cKDTree(boundary), cKDTree(vein_points)
    for i in np.flatnonzero(tied):
        b_near = boundary[b_tree.query_ball_point(xy[i], d_b[i] * (1 + TIE) + 1e-15)]
        v_near = vein_points[v_tree.query_ball_point(xy[i], d_v[i] * (1 + TIE) + 1e-15)]
        reach[i] = np.linalg.norm(b_near[:, None] - v_near[None], axis=2).mean()
