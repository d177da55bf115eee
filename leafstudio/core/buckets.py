"""Support for steps 2, 3 and 5 (no step of its own): a uniform bucket grid over 2D points, for the
compiled (numba) neighbour searches in core.

The MPU implicit, the height guide and the mesher ask, for many query points at once, which cells
or data points lie near each query. Sorting the queries into square buckets once (a counting
sort, O(n)) lets a compiled loop visit only the buckets a support disc or a search box overlaps.

Core's compiled kernels use ``@njit(cache=True, nogil=True)``: numba keeps the machine code on
disk (a fresh install compiles once, for some seconds; later processes load it in a fraction of
a second), and the app's main thread keeps running while a kernel does.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from leafstudio.core.jit import njit

PER_BUCKET = 4  # points per bucket on average over the points' bounding box
CROWDED_BUCKET = 64  # neighbour_distances hands a set with a bucket this full to a k-d tree


class Buckets(NamedTuple):
    """Points sorted into an (ny, nx) grid of square buckets of side `size` from `lo`.

    The points of bucket b = iy * nx + ix are ``order[starts[b]:starts[b + 1]]``. A named tuple:
    compiled kernels take it whole (numba types it as one argument).
    """

    lo: np.ndarray  # (2,) float
    size: float
    nx: int
    ny: int
    starts: np.ndarray  # (nx * ny + 1,) int64
    order: np.ndarray  # (n,) int64


def kernel_array(array: np.ndarray, dtype: type = float) -> np.ndarray:
    """`array` as a C-contiguous, writeable array of `dtype`, as every compiled kernel here takes
    it: numba types a read-only array apart and would compile (and cache) each kernel again."""
    out = np.ascontiguousarray(array, dtype=dtype)
    return out if out.flags.writeable else out.copy()


def frozen_array(array: np.ndarray, dtype: type = float) -> np.ndarray:
    """`array` as a C-contiguous, read-only view of `dtype`: for a kernel whose inputs are
    usually kept (read-only) results, one compiled signature without copying them."""
    out = np.ascontiguousarray(array, dtype=dtype).view()
    out.flags.writeable = False
    return out


def bucket_points(
    xy: np.ndarray, size: float | None = None, per_bucket: float = PER_BUCKET
) -> Buckets:
    """Sort (n, 2) points into square buckets of side `size` (default: about `per_bucket` points
    per bucket over their bounding box)."""
    xy = kernel_array(xy)
    lo, hi = bounds(xy) if len(xy) else (np.zeros(2), np.ones(2))
    side = _side(lo, hi, len(xy), size, per_bucket)  # in Python floats: the same figures
    if side is not None:
        size, nx, ny = side
        starts, order = _counting_sort(xy, lo, size, nx, ny)
        return Buckets(lo=lo, size=size, nx=nx, ny=ny, starts=starts, order=order)
    extent = np.maximum(hi - lo, 1e-300)
    if size is None:
        size = float(np.sqrt(extent[0] * extent[1] * per_bucket / max(len(xy), 1)))
        size = max(size, float(extent.max()) / 4096)
        if float(extent.max()) <= 1e-300:  # one point, or all at one place: one bucket (the
            size = 1.0  # side above, 1e-304, made 4097² buckets and overflowed the indices)
    nx, ny = (np.floor(extent / size).astype(np.int64) + 1).tolist()
    starts, order = _counting_sort(xy, lo, float(size), nx, ny)
    return Buckets(lo=lo, size=float(size), nx=int(nx), ny=int(ny), starts=starts, order=order)


def _side(
    lo: np.ndarray, hi: np.ndarray, n: int, size: float | None, per_bucket: float
) -> tuple[float, int, int] | None:
    """bucket_points' side and bucket counts from the (2,) box `lo`, `hi` of n points, its
    numpy steps done in Python floats (the same IEEE operations, in the same order; numpy's
    dozen calls on two-element arrays: bucket_points 36 -> 19 us at a flat ovate's 500
    outline points at grid 128 on a busy host, nine calls a run; the same buckets on 5000 random
    sets, /work/notes/cpu39/micro_side.py); None where a figure is not finite or the counts
    would not fit numpy's int64 (numpy's own steps)."""
    (x0, y0), (x1, y1) = lo.tolist(), hi.tolist()
    ex, ey = max(x1 - x0, 1e-300), max(y1 - y0, 1e-300)
    if not (math.isfinite(ex) and math.isfinite(ey)):
        return None
    if size is None:
        size = math.sqrt(ex * ey * per_bucket / max(n, 1))
        size = max(size, max(ex, ey) / 4096)
        if max(ex, ey) <= 1e-300:
            size = 1.0
    size = float(size)
    if not (size > 0 and ex / size < 2**62 and ey / size < 2**62):
        return None
    return size, math.floor(ex / size) + 1, math.floor(ey / size) + 1


def bounds(
    xy: np.ndarray, numpys: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(d,) lower and upper corners of the box around (n >= 1, d) points, column by column
    (numpy's min(axis=0) on an (n, 2) array is many times slower; np.ptp over axis 0 of a
    grid-128 mesh's 7,300 points took 0.38 ms, numpy's reductions column by column 0.03).
    Compiled (_bounds) for C-ordered doubles: numpy's four reductions and two arrays took 8.3 to
    31 us at a flat ovate's 500 to 7,300 points at grid 128, where bounds runs 12 times a run,
    _bounds 1.9 to 20, best of 9 x 300 (/work/notes/cpu39/micro_bounds.py). A bound that is ±0
    or NaN is numpy's: any other least or largest value has one bit pattern, whichever element
    gave it. `numpys`: the caller's own numpy reduction for those (a min(axis=0) may give a ±0
    the other sign), else numpy's column by column."""
    xy = np.asarray(xy)
    if xy.dtype == np.float64 and xy.ndim == 2 and xy.flags.c_contiguous and len(xy):
        lo, hi, numpy_wanted = _bounds(xy)
        if not numpy_wanted:
            return lo, hi
    if numpys is not None:
        return numpys(xy)
    columns = xy.T
    return np.array([c.min() for c in columns]), np.array([c.max() for c in columns])


def median(values: np.ndarray) -> float:
    """float(np.median(values)) of a 1-D float array, to the bit: the middle one or two of a
    partition, their mean as numpy's (a + b) / 2; numpy's own for none, a NaN or a zero median
    (a ±0 sum). np.median took 12-23 us a call at 60-2000 values (a flat ovate's 500 outline
    points at grid 128: 19, six calls a run), this 3.5-15 (/work/notes/cpu39/micro_median.py)."""
    n = len(values)
    if n and values.dtype == np.float64:
        half = n // 2
        part = np.partition(values, (half - 1, half, n - 1) if n % 2 == 0 else (half, n - 1))
        middle = part[half] if n % 2 else (part[half - 1] + part[half]) / 2
        if middle != 0 and not np.isnan(part[-1]):  # NaN: sorted last
            return float(middle)
    return float(np.median(values))


@njit(cache=True, nogil=True)
def _bounds(xy):
    """The columns' least and largest values of the (n >= 1, d) `xy`, and whether numpy's are
    wanted instead (a NaN, or a bound ±0)."""
    n, d = xy.shape
    lo, hi = np.empty(d), np.empty(d)
    numpys = False
    for k in range(d):
        least, most = xy[0, k], xy[0, k]
        for i in range(n):
            v = xy[i, k]
            least = v if v < least else least
            most = v if v > most else most
            numpys |= v != v
        lo[k], hi[k] = least, most
        numpys |= least == 0 or most == 0
    return lo, hi, numpys


@njit(cache=True, nogil=True)
def _counting_sort(xy, lo, size, nx, ny):
    """Bucket starts and the point indices sorted by bucket, stable, in O(n)."""
    n = len(xy)
    key = np.empty(n, np.int64)
    starts = np.zeros(nx * ny + 1, np.int64)
    for i in range(n):
        ix = min(int((xy[i, 0] - lo[0]) / size), nx - 1)
        iy = min(int((xy[i, 1] - lo[1]) / size), ny - 1)
        key[i] = iy * nx + ix
        starts[key[i] + 1] += 1
    for b in range(nx * ny):
        starts[b + 1] += starts[b]
    fill = np.empty(nx * ny, np.int64)
    for b in range(nx * ny):  # not a slice's copy: code of its own at the first run's compile
        fill[b] = starts[b]
    order = np.empty(n, np.int64)
    for i in range(n):
        order[fill[key[i]]] = i
        fill[key[i]] += 1
    return starts, order


def neighbour_distances(points: np.ndarray, which: np.ndarray) -> np.ndarray:
    """Distance from each of the points `which` indexes to its nearest other point of the (n, 2)
    distinct `points` (inf when n == 1): a few microseconds a query, where a k-d tree first
    spends milliseconds building over tens of thousands of points."""
    points = kernel_array(points)
    if len(points) < 2:
        return np.full(len(which), np.inf)
    # points along a curve (an outline) crowd a few of the box's buckets: finer ones keep each
    # query's scan short, and cost only empty buckets where the points fill the box
    b = bucket_points(points, per_bucket=0.25)
    if np.diff(b.starts).max() > CROWDED_BUCKET:  # a tight cluster in a wide box: scans would
        from scipy.spatial import cKDTree  # grow with its square; a k-d tree does not

        return cKDTree(points).query(points[which], k=2)[0][:, 1]
    return _neighbour_distances(points, np.asarray(which, dtype=np.int64), b)


@njit(cache=True, nogil=True)
def _ring(cx, cy, ring, nx, ny, cells):
    """How many buckets lie `ring` steps out from bucket (cx, cy), within the nx × ny buckets:
    their indices, row by row, in the first slots of `cells` (the searches outward share it)."""
    count = 0
    for by in range(max(cy - ring, 0), min(cy + ring, ny - 1) + 1):
        on_edge_row = by == cy - ring or by == cy + ring
        step = 1 if on_edge_row else 2 * ring
        for bx in range(cx - ring, cx + ring + 1, max(step, 1)):
            if 0 <= bx < nx:
                cells[count] = by * nx + bx
                count += 1
    return count


@njit(cache=True, nogil=True)
def _neighbour_distances(points, which, b):
    """Rings of buckets outward from each query's own until the ring's nearest possible point
    (ring - 1 buckets away) is farther than the best found."""
    lo, size, nx, ny, starts, order = b
    out = np.empty(len(which))
    cells = np.empty(8 * max(nx, ny) + 8, dtype=np.int64)  # a ring's buckets (_ring)
    for q in range(len(which)):
        i = which[q]
        px, py = points[i, 0], points[i, 1]
        cx = min(int((px - lo[0]) / size), nx - 1)
        cy = min(int((py - lo[1]) / size), ny - 1)
        best = np.inf
        ring = 0
        while ring <= max(nx, ny) and (ring - 1) * size <= np.sqrt(best):
            for c in range(_ring(cx, cy, ring, nx, ny, cells)):
                k = cells[c]
                for s in range(starts[k], starts[k + 1]):
                    j = order[s]
                    if j != i:
                        d2 = (points[j, 0] - px) ** 2 + (points[j, 1] - py) ** 2
                        best = min(best, d2)
            ring += 1
        out[q] = np.sqrt(best)
    return out


@njit(cache=True, nogil=True)
def kth_distances(points, centers, k, b):
    """(m,) distance from each centre to its k-th nearest of the (n, 2) points (bucketed in
    the Buckets b; inf when n < k), the square root of dx² + dy² as scipy's cKDTree.query(
    centers, k)[0][:, -1] gives it: rings of buckets outward from the centre's (clamped to
    the buckets) until the ring's nearest possible point is farther than the k-th found. In
    place of the k-d tree's build and queries, mpu.build_mpu's grown balls: 1.53 -> 1.20 ms
    on a flat ovate at grid 128 (best of 40; the same radii to the bit)."""
    lo, size, nx, ny, starts, order = b
    out = np.empty(len(centers))
    cells = np.empty(8 * max(nx, ny) + 8, dtype=np.int64)  # a ring's buckets (_ring)
    best = np.empty(k)  # the k least squared distances so far, ascending
    for q in range(len(centers)):
        px, py = centers[q, 0], centers[q, 1]
        for j in range(k):
            best[j] = np.inf
        cx = min(max(math.floor((px - lo[0]) / size), 0), nx - 1)
        cy = min(max(math.floor((py - lo[1]) / size), 0), ny - 1)
        ring = 0
        # a margin over the bound: the buckets' edges are rounded as the points were sorted
        while ring <= max(nx, ny) and (ring - 1) * size <= np.sqrt(best[k - 1]) * (1 + 1e-9):
            for c in range(_ring(cx, cy, ring, nx, ny, cells)):
                cell = cells[c]
                for s in range(starts[cell], starts[cell + 1]):
                    j = order[s]
                    dx, dy = px - points[j, 0], py - points[j, 1]
                    d2 = dx * dx + dy * dy
                    if d2 < best[k - 1]:
                        slot = k - 1
                        while slot > 0 and best[slot - 1] > d2:
                            best[slot] = best[slot - 1]
                            slot -= 1
                        best[slot] = d2
            ring += 1
        out[q] = np.sqrt(best[k - 1])
    return out


@njit(cache=True, nogil=True)
def bucket_span(low: float, high: float, lo: float, size: float, count: int) -> tuple[int, int]:
    """The first and last bucket, along one axis, that the interval [low, high] overlaps."""
    first = max(math.floor((low - lo) / size), 0)
    last = min(math.floor((high - lo) / size), count - 1)
    return first, last


@njit(cache=True, nogil=True)
def gather(b, x_low, x_high, y_low, y_high, out):
    """The bucket walk, written once: the indices of the points in every bucket that the box
    [x_low, x_high] x [y_low, y_high] overlaps, bucket by bucket in row order, into `out`
    (an (n,) int64 buffer, n the number of points: each point lies in one bucket); returns
    their count. The caller tests each candidate against its own disc or segment."""
    x0, x1 = bucket_span(x_low, x_high, b.lo[0], b.size, b.nx)
    y0, y1 = bucket_span(y_low, y_high, b.lo[1], b.size, b.ny)
    count = 0
    for by in range(y0, y1 + 1):
        for k in range(by * b.nx + x0, by * b.nx + x1 + 1):
            for j in range(b.starts[k], b.starts[k + 1]):
                out[count] = b.order[j]
                count += 1
    return count


def near_edges(polygon: np.ndarray, xy: np.ndarray, radius: float) -> np.ndarray:
    """(n,) bool: which of the (n, 2) points lie within `radius` of an edge of the closed
    (b, 2) polygon; each edge visits only the buckets its box (grown by `radius`) covers."""
    xy = kernel_array(xy)
    near = np.zeros(len(xy), dtype=bool)
    if len(xy) == 0:
        return near
    _mark_near_edges(kernel_array(polygon), xy, float(radius), bucket_points(xy), near)
    return near


@njit(cache=True, nogil=True)
def _mark_near_edges(polygon, xy, radius, b, near):
    """Set near[i] for the points within `radius` of an edge of the closed polygon."""
    n = len(polygon)
    candidates = np.empty(len(xy), np.int64)
    for e in range(n):
        ax, ay = polygon[e, 0], polygon[e, 1]
        bx, by = polygon[(e + 1) % n, 0], polygon[(e + 1) % n, 1]
        ex, ey = bx - ax, by - ay
        length2 = ex * ex + ey * ey
        count = gather(
            b, min(ax, bx) - radius, max(ax, bx) + radius, min(ay, by) - radius,
            max(ay, by) + radius, candidates,
        )  # fmt: skip
        for s in range(count):
            i = candidates[s]
            px, py = xy[i, 0] - ax, xy[i, 1] - ay
            t = (px * ex + py * ey) / length2 if length2 > 0 else 0.0
            t = min(max(t, 0.0), 1.0)
            if (px - t * ex) ** 2 + (py - t * ey) ** 2 <= radius * radius:
                near[i] = True
