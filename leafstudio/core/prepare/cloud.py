"""Boundary clouds as scanners give them: noisy, unordered, dense; in linear time.

Three steps; the last two do not depend on the order the points were given in:

- `estimate_noise`: the points' scatter across the outline (and in height), from how far each
  point lies from the cubic through its neighbours along an order round the outline (the given
  one, or the one `point_order` finds);
- `order_cells`: the points summed into square cells (one bucket pass, O(n)), the occupied cells
  closed into a band on a raster, and the band's outer contour round the hole it encloses
  (contourpy) as a guide that gives every cell a position along the outline;
- `mean_outline`: the cells' points binned along that position and smoothed (a local quadratic
  fit, which keeps curvature): the outline follows the points' mean position, heights too.

outline.py decides from the estimated noise whether a cloud is clean (its points become the
outline's vertices, in the order this module finds) or noisy (the smooth mean outline).
"""

from __future__ import annotations

from dataclasses import dataclass

import contourpy
import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from leafstudio.core.buckets import bounds, kernel_array, median
from leafstudio.core.jit import njit
from leafstudio.core.kernels import ensure_compiled

NOISE_SAMPLE = 20000  # points whose prediction misses estimate the noise, at most
MAX_GROWTH = 8  # the occupied cells are grown by at most this many to close round the inside
GUIDE_SMOOTHING = 3  # the guide contour is averaged over this many vertices either side
FILLED_KEEP = 0.9  # the region a filled cloud covers holds at least this share of its points
MAX_BINS = 3000  # the mean outline's vertices, at most
OUTLINE_STEP = 1 / 1000  # the mean outline's vertex spacing, as a fraction of the cloud's size
SMOOTH_NOISE = 4.0  # the smoothing window's half width: this many noise σ ...
SMOOTH_POINTS = 8  # ... and at least the arc this many input points take


@dataclass(frozen=True)
class Noise:
    """Estimated scatter of a boundary cloud: σ across the outline in the plane, σ in height."""

    across: float
    height: float


PREDICT = np.array([-1 / 6, 2 / 3, 2 / 3, -1 / 6])  # point i from i-2, i-1, i+1, i+2 (exact on
# cubics in the index); the residual's variance is then (1 + |PREDICT|^2) sigma^2 of the noise
CHI2_MEDIAN = 0.454936  # the median of chi-squared with one degree of freedom
CHI2_MEDIAN_MEAN = 0.6  # about the median of a cell's mean square (a few points averaged)


def estimate_noise(xy: np.ndarray, z: np.ndarray, sequence: np.ndarray) -> Noise:
    """The scatter of (n, 2) boundary points across their outline, and of their heights `z`,
    with the points taken in `sequence` (indices round the outline, closed).

    Each point is predicted from its two neighbours either side by the cubic through them (in
    the index) and the miss is measured across the outline (perpendicular to the chord from the
    second neighbour behind to the second ahead): on a clean curve it is tiny whatever the
    spacing, and for isotropic noise of σ its variance is (1 + |PREDICT|²) σ² even when the
    points are so dense that the chord's direction is itself noise. The median over points
    ignores the few at a tip or a corner.
    """
    if len(sequence) < 8:
        return Noise(0.0, 0.0)
    step = max(1, len(sequence) // NOISE_SAMPLE)
    across, height = _prediction_misses(
        kernel_array(xy), kernel_array(z), np.asarray(sequence, dtype=np.int64), step
    )
    scale = (1 + float(PREDICT @ PREDICT)) * CHI2_MEDIAN
    return Noise(float(np.sqrt(median(across) / scale)), float(np.sqrt(median(height) / scale)))


def _prediction_misses(
    xy: np.ndarray, z: np.ndarray, sequence: np.ndarray, step: int
) -> tuple[np.ndarray, np.ndarray]:
    """Squared misses (across, in height) of the cubic prediction at every `step`-th point of
    the closed ring xy[sequence]. (Not compiled: at most NOISE_SAMPLE points, 0.25 ms for a
    million-point ring, where it cost 0.3 s of the first run's compile.)"""
    n = len(sequence)
    i = np.arange(0, n, step)
    p = sequence[i]
    a, b, c, d = (sequence[(i + shift) % n] for shift in (-2, -1, 1, 2))
    c0, c1 = -1 / 6, 2 / 3
    px = c0 * (xy[a, 0] + xy[d, 0]) + c1 * (xy[b, 0] + xy[c, 0])
    py = c0 * (xy[a, 1] + xy[d, 1]) + c1 * (xy[b, 1] + xy[c, 1])
    pz = c0 * (z[a] + z[d]) + c1 * (z[b] + z[c])
    tx, ty = xy[d, 0] - xy[a, 0], xy[d, 1] - xy[a, 1]
    norm = np.sqrt(tx * tx + ty * ty)
    miss = -(xy[p, 0] - px) * ty + (xy[p, 1] - py) * tx
    across = np.divide(miss, norm, out=np.zeros(len(i)), where=norm > 0)
    return across * across, (z[p] - pz) ** 2


@dataclass(frozen=True)
class Cells:
    """The cloud summed into square cells, each placed along the outline.

    Attributes
    ----------
    of_point : (n,) int array
        Each point's cell (an index into the arrays below).
    count : (m,) float array
        Points per occupied cell.
    mean : (m, 2) float array
        Mean position of each cell's points.
    mean_z : (m,) float array
        Mean height of each cell's points.
    spread : (m, 4) float array
        Each cell's points' (co)variances about their mean: xx, xy, yy and zz.
    t : (m,) float array
        Each cell's position along the guide contour (arc length from its start).
    perimeter : float
        The guide's length.
    """

    of_point: np.ndarray
    count: np.ndarray
    mean: np.ndarray
    mean_z: np.ndarray
    spread: np.ndarray
    t: np.ndarray
    perimeter: float


def order_cells(xy: np.ndarray, z: np.ndarray, cell: float) -> Cells | None:
    """The (n, 2) points summed into cells of side `cell` and placed along a guide contour.

    The occupied cells are grown (one cell at a time, up to MAX_GROWTH) until they close round
    a hole holding at least a fifth of the region they enclose: the leaf's inside. The grown
    band's outline round it, traced by contourpy, is the guide. None if no growth closes one.
    """
    xy = kernel_array(xy)
    lo, hi = bounds(xy)
    nx, ny = (np.floor((hi - lo) / cell).astype(np.int64) + 1).tolist()
    ix = np.minimum(((xy[:, 0] - lo[0]) / cell).astype(np.int64), nx - 1)
    iy = np.minimum(((xy[:, 1] - lo[1]) / cell).astype(np.int64), ny - 1)
    key = iy * nx + ix
    counts = np.bincount(key, minlength=nx * ny)
    occupied = counts > 0
    cell_index = np.cumsum(occupied) - 1
    of_point = cell_index[key]
    count = counts[occupied].astype(float)
    m = len(count)
    sx = np.bincount(of_point, weights=xy[:, 0], minlength=m)
    sy = np.bincount(of_point, weights=xy[:, 1], minlength=m)
    sz = np.bincount(of_point, weights=z, minlength=m)
    mean = np.column_stack([sx / count, sy / count])
    mean_z = sz / count
    dx, dy, dz = xy[:, 0] - mean[of_point, 0], xy[:, 1] - mean[of_point, 1], z - mean_z[of_point]
    spread = np.column_stack(
        [np.bincount(of_point, weights=a * b, minlength=m) / count
         for a, b in ((dx, dx), (dx, dy), (dy, dy), (dz, dz))]
    )  # fmt: skip

    guide = _guide(occupied.reshape(ny, nx), MAX_GROWTH)
    if guide is None:
        return None
    guide = lo + (guide + 0.5) * cell  # raster cell centres to the plane
    if len(guide) > 4 * GUIDE_SMOOTHING:  # the raster's staircase, smoothed: its direction
        kernel = np.ones(2 * GUIDE_SMOOTHING + 1) / (2 * GUIDE_SMOOTHING + 1)  # orders points
        wrapped = np.vstack([guide[-GUIDE_SMOOTHING:], guide, guide[:GUIDE_SMOOTHING]])
        guide = np.column_stack([np.convolve(wrapped[:, k], kernel, "valid") for k in range(2)])
    edges = np.roll(guide, -1, axis=0) - guide
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    arc = np.concatenate([[0.0], np.cumsum(lengths)])
    nearest = cKDTree(guide).query(mean)[1]
    t = _project(mean, nearest, guide, edges, lengths, arc, reach=1)
    return Cells(of_point, count, mean, mean_z, spread, t, float(arc[-1]))


def _guide(occupied: np.ndarray, most: int) -> np.ndarray | None:
    """(k, 2) the outer outline of the band of occupied raster cells grown by up to `most`
    cells round the hole it encloses (the leaf's inside), in cell units (x = column, y = row),
    not closed; None if it never encloses a hole of at least a fifth of the region. The outer
    edge, not the hole's: a narrow tip or base, where the band closes over, stays on it."""
    pad = most + 1
    band = np.pad(occupied, pad)
    for _ in range(most):
        band = ndimage.binary_dilation(band)
        labels, n = ndimage.label(~band)  # the outside, and the holes the band encloses
        if n < 2:
            continue
        outside = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
        sizes = np.bincount(labels.ravel(), minlength=n + 1)
        sizes[outside] = 0
        sizes[0] = 0  # the band itself
        filled = ~np.isin(labels, outside)
        if sizes.max() < 0.2 * np.count_nonzero(filled):
            continue
        lines = contourpy.contour_generator(z=filled.astype(float)).lines(0.5)
        line = max(lines, key=len)
        if len(line) < 4:
            return None
        line = line[:-1] if np.allclose(line[0], line[-1]) else line
        return line - pad
    return None


def filled_outline(xy: np.ndarray, z: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """(k, 2) outline and (k,) heights of the region a cloud fills: for points that cover the
    leaf rather than trace its margin (order_cells finds no inside). The occupied cells of side
    `cell`, closed by two cells, their largest filled part's contour; heights of the nearest
    points. The cell doubles while that part holds under FILLED_KEEP of the points (a scan's
    stripes lie farther apart than its points along them)."""
    xy = kernel_array(xy)
    lo, hi = bounds(xy)
    while True:
        nx, ny = (np.floor((hi - lo) / cell).astype(np.int64) + 1).tolist()
        ix = np.minimum(((xy[:, 0] - lo[0]) / cell).astype(np.int64), nx - 1)
        iy = np.minimum(((xy[:, 1] - lo[1]) / cell).astype(np.int64), ny - 1)
        occupied = np.zeros((ny + 6, nx + 6), dtype=bool)
        occupied[iy + 3, ix + 3] = True
        region = ndimage.binary_fill_holes(ndimage.binary_closing(occupied, iterations=2))
        labels = ndimage.label(region)[0]
        biggest = int(np.argmax(np.bincount(labels.ravel())[1:])) + 1
        if np.mean(labels[iy + 3, ix + 3] == biggest) >= FILLED_KEEP or max(nx, ny) <= 16:
            break
        cell *= 2
    line = max(contourpy.contour_generator(z=(labels == biggest).astype(float)).lines(0.5), key=len)
    line = line[:-1] if np.allclose(line[0], line[-1]) else line
    outline = lo + (line - 3 + 0.5) * cell
    return outline, z[cKDTree(xy).query(outline)[1]]


def _project(
    points: np.ndarray,
    near: np.ndarray,
    ring: np.ndarray,
    edges: np.ndarray,
    lengths: np.ndarray,
    arc: np.ndarray,
    reach: int,
) -> np.ndarray:
    """Arc position along the closed `ring` of each point's nearest place on the edges within
    `reach` of its vertex `near`."""
    t = np.empty(len(points))
    ensure_compiled()
    _project_kernel(
        kernel_array(points), np.asarray(near, dtype=np.int64), kernel_array(ring),
        kernel_array(edges), kernel_array(lengths), kernel_array(arc), reach, t,
    )  # fmt: skip
    return t


@njit(cache=True, nogil=True)
def _project_kernel(points, near, ring, edges, lengths, arc, reach, t):
    k = len(ring)
    for i in range(len(points)):
        best = np.inf
        for shift in range(-reach, reach + 1):
            e = (near[i] + shift) % k
            rx, ry = points[i, 0] - ring[e, 0], points[i, 1] - ring[e, 1]
            ex, ey = edges[e, 0], edges[e, 1]
            length = max(lengths[e], 1e-300)
            s = min(max((rx * ex + ry * ey) / (length * length), 0.0), 1.0)
            d = (rx - s * ex) ** 2 + (ry - s * ey) ** 2
            if d < best:
                best = d
                t[i] = arc[e] + s * lengths[e]


def point_order(cells: Cells, xy: np.ndarray) -> np.ndarray:
    """Indices of the (n, 2) points in order along the outline (for a clean curve, its own
    order): by their place along the chain of the cells' means in the guide's order, found on
    the chain's few edges about their own cell's mean. The chain runs through the points
    themselves, so, unlike the guide a cell or two inside them, it does not bunch the places of
    points at its corners."""
    by_t = np.argsort(cells.t, kind="stable")
    chain = cells.mean[by_t]
    rank = np.empty(len(by_t), np.int64)
    rank[by_t] = np.arange(len(by_t))
    edges = np.roll(chain, -1, axis=0) - chain
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    arc = np.concatenate([[0.0], np.cumsum(lengths)])
    t = _project(xy, rank[cells.of_point], chain, edges, lengths, arc, reach=2)
    return np.argsort(t, kind="stable")


def mean_outline(
    cells: Cells, n_points: int, size: float, wider: float = 1.0
) -> tuple[np.ndarray, np.ndarray, Noise]:
    """(k, 2) vertices and (k,) heights of the smooth outline through the cells' mean position,
    and the points' scatter about it.

    The cells are binned along the guide at about OUTLINE_STEP of `size` (the cloud's size) and
    the outline at each bin is a local quadratic fit, with Gaussian weights of SMOOTH_NOISE noise
    σ either side (at least the arc SMOOTH_POINTS of the `n_points` take) times each bin's point
    count, to the bins' means (_local_fit): the noise averages out, the shape's curvature does
    not, and a bin holding only a few stray points weighs only as much as they do. σ is measured
    about the outline itself (_scatter), twice over, so that it and the outline depend on the
    points, not on the order they came in. `wider` widens the weights (sparse points whose
    outline folds).
    """
    perimeter = cells.perimeter
    bins = int(np.clip(perimeter / (OUTLINE_STEP * size), 16, MAX_BINS))
    width = perimeter / bins
    which = np.minimum((cells.t / width).astype(np.int64), bins - 1)
    weight = np.bincount(which, weights=cells.count, minlength=bins)
    sums = np.column_stack(
        [
            np.bincount(which, weights=cells.count * v, minlength=bins)
            for v in (cells.mean[:, 0], cells.mean[:, 1], cells.mean_z)
        ]
    )
    least = 0.5 * SMOOTH_POINTS * perimeter / max(n_points, 1)
    noise = Noise(0.0, 0.0)
    for rounds in range(3):
        half = wider * max(SMOOTH_NOISE * max(noise.across, noise.height), least, 2 * width)
        curve = _local_fit(weight, sums, min(0.5 * half / width, bins / 8))
        if rounds < 2:
            noise = _scatter(cells, curve, cells.t / width)
    return curve[:, :2], curve[:, 2], noise


def _local_fit(weight: np.ndarray, sums: np.ndarray, sigma: float) -> np.ndarray:
    """(k, 3) the closed curve whose bins hold `weight` points summing to `sums`, each bin the
    value at it of the quadratic fitted to the bins about it with weights exp(-j²/2σ²) times
    their point counts (j bins away); where too few bins hold points for a quadratic, their
    weighted mean."""
    reach = int(np.ceil(4 * sigma))
    j = np.arange(-reach, reach + 1, dtype=float)
    g = np.exp(-0.5 * (j / sigma) ** 2)
    moment = [ndimage.correlate1d(weight, g * j**p, mode="wrap") for p in range(5)]
    fit = [
        np.column_stack([ndimage.correlate1d(sums[:, c], g * j**p, mode="wrap") for c in range(3)])
        for p in range(3)
    ]
    matrix = np.stack(
        [np.stack([moment[r + c] for c in range(3)], axis=-1) for r in range(3)], axis=-2
    )  # (k, 3, 3)
    rhs = np.stack(fit, axis=1)  # (k, 3 powers, 3 coordinates)
    mean = fit[0] / np.maximum(moment[0], 1e-300)[:, None]
    det = np.linalg.det(matrix)
    ok = det > 1e-9 * np.maximum(moment[0], 1e-300) ** 3 * sigma**6
    out = mean.copy()
    if ok.any():
        out[ok] = np.linalg.solve(matrix[ok], rhs[ok])[:, 0, :]
    return out


def _scatter(cells: Cells, curve: np.ndarray, at: np.ndarray) -> Noise:
    """The points' scatter about the closed (k, 3) curve, sampled at bins 0..k-1, the cells
    lying at bin positions `at`: each cell's variance across the curve and in height (its own
    spread and its mean's offset), the median over points (weighted by count)."""
    k = len(curve)
    index = np.arange(k + 1)
    closed = np.vstack([curve, curve[:1]])
    place = np.column_stack([np.interp(at, index, closed[:, j]) for j in range(3)])
    ahead = np.column_stack([np.interp((at + 1) % k, index, closed[:, j]) for j in range(2)])
    behind = np.column_stack([np.interp((at - 1) % k, index, closed[:, j]) for j in range(2)])
    tangent = ahead - behind
    tangent /= np.maximum(np.hypot(tangent[:, 0], tangent[:, 1]), 1e-300)[:, None]
    nx, ny = -tangent[:, 1], tangent[:, 0]
    xx, xy, yy, zz = cells.spread.T
    off = (cells.mean[:, 0] - place[:, 0]) * nx + (cells.mean[:, 1] - place[:, 1]) * ny
    across = nx * nx * xx + 2 * nx * ny * xy + ny * ny * yy + off * off
    height = zz + (cells.mean_z - place[:, 2]) ** 2
    return Noise(
        float(np.sqrt(_weighted_median(across, cells.count) / CHI2_MEDIAN_MEAN)),
        float(np.sqrt(_weighted_median(height, cells.count) / CHI2_MEDIAN_MEAN)),
    )


def _weighted_median(values: np.ndarray, weights: np.ndarray) -> float:
    """The median of `values` each counted `weights` times (order-free)."""
    order = np.argsort(values, kind="stable")
    total = np.cumsum(weights[order])
    return float(values[order][np.searchsorted(total, 0.5 * total[-1])])
