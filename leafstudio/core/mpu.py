"""Step 2 (section 3.2): the 2D multi-level partition-of-unity implicit g(x) of section 3.2 (Ohtake
et al.).

g(x) = Σ w_i(x) f_i(x) / Σ w_i(x)                                    (eq. 1)

Each f_i is a linear function fitted to the oriented boundary points inside a ball around the
centre of one adaptive quadtree cell; the cell is split until the fit is within the tolerance.
w_i(x) = b(|x − c_i| / r_i) with b the quadratic B-spline of eq. 2, so g is C1 everywhere.
Eq. 2 as printed writes b(3|x − c_i| / (2 r_i)), which applies Ohtake et al.'s factor 3/2 twice:
their B-spline lives on [0, 3/2) and the paper's b is that spline already rescaled to [0, 1). Taken
literally, a cell's weight would end at 2 r_i / 3, half its diagonal, leaving the cell's corners
with almost no weight and g with gaps; with b(|x − c_i| / r_i) each support reaches r_i, as in
Ohtake et al.
g > 0 inside the leaf, g = 0 on its margin, g < 0 outside; near the margin g is close to the
signed distance, because each f_i has a unit gradient.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.spatial import cKDTree

from leafstudio.core.buckets import (
    bounds,
    bucket_points,
    gather,
    kernel_array,
    kth_distances,
    median,
    neighbour_distances,
)
from leafstudio.core.grid import Grid
from leafstudio.core.jit import njit

ALPHA = 0.75  # support radius = ALPHA * cell diagonal (Ohtake et al.)
N_MIN = 6  # a ball grows until it holds this many points
MIN_NORMAL_AGREEMENT = 0.5  # cos of the largest angle between a cell's normals and their mean
MAX_DEPTH = 12


class Cells(NamedTuple):
    """The implicit's cells as the compiled loops take them: centres c_i (m, 2), support radii
    r_i (m,), and f_i's coefficients (m, 3)."""

    centers: np.ndarray
    radii: np.ndarray
    coef: np.ndarray


class Cell(NamedTuple):
    """One cell inside a compiled loop: its centre, 1 / r_i, and f_i = a x + b y + e."""

    cx: float
    cy: float
    scale: float
    a: float
    b: float
    e: float


class Sums(NamedTuple):
    """D = Σ w_i and N = Σ w_i f_i at each query (n,), their gradients (n, 2) and Hessians as
    (xx, xy, yy) (n, 3); the derivatives are empty (0 rows) when not asked for."""

    big_d: np.ndarray
    big_n: np.ndarray
    grad_d: np.ndarray
    grad_n: np.ndarray
    hess_d: np.ndarray
    hess_n: np.ndarray


class Lattice(NamedTuple):
    """A regular grid as the compiled loops take it: node (ix, iy) at (ox + spacing ix,
    oy + spacing iy), nx by ny nodes."""

    ox: float
    oy: float
    spacing: float
    nx: int
    ny: int


def bspline_weight(t: np.ndarray) -> np.ndarray:
    """The weight b(t) of eq. 2: 3/4 at t = 0, 0 from t = 1 on, C1 in between."""
    t = np.abs(t)
    return np.where(t < 1 / 3, 0.75 - 2.25 * t**2, np.where(t < 1, 1.125 * (t - 1) ** 2, 0.0))


@dataclass(frozen=True)
class MPUImplicit:
    """The fitted implicit: one linear function per quadtree leaf cell.

    Attributes
    ----------
    centers : (m, 2) float array
        Cell centres c_i.
    radii : (m,) float array
        Support radii r_i.
    coef : (m, 3) float array
        f_i(x, y) = coef[i, 0] x + coef[i, 1] y + coef[i, 2].
    points : (n, 2) float array
        The boundary points it was fitted to (for the far-field fallback).
    depth : (m,) int array
        Quadtree depth of each cell.
    """

    centers: np.ndarray
    radii: np.ndarray
    coef: np.ndarray
    points: np.ndarray
    depth: np.ndarray

    def evaluate(self, xy: np.ndarray, gradient: bool = False):
        """g at (n, 2) points; with `gradient`, also its (n, 2) gradient.

        Outside every support (far from the leaf) g is minus the distance to the nearest
        boundary point, and the gradient points toward it.
        """
        g, grad, _ = self._blend(xy, 1 if gradient else 0)
        return (g, grad) if gradient else g

    def derivatives(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """g (n,), ∇g (n, 2) and ∇²g (n, 2, 2) at (n, 2) points, in closed form.

        With N = Σ w_i f_i and D = Σ w_i (eq. 1), ∇²g = (∇²N − g ∇²D − ∇g ∇Dᵀ − ∇D ∇gᵀ) / D.
        Piecewise: the B-splines are C1, so ∇²g jumps where a point crosses t = 1/3 or t = 1 of
        some cell. Far from the leaf (no support covers the point) g = −|x − b| and
        ∇²g = −(I − u uᵀ) / |x − b| with u = ∇g.
        """
        return self._blend(xy, 2)

    def on_grid(self, grid: Grid) -> np.ndarray:
        """g at every node of a regular grid, (ny * nx,) in grid order: the same values as
        evaluate(grid.points), summed row by row over each cell's support (no buckets)."""
        return self._grid_blend(grid, np.ones(grid.shape[0] * grid.shape[1], bool), 0)[0]

    def derivatives_on_grid(
        self, xy: np.ndarray, grid: Grid, nodes: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """`derivatives(xy)` where xy ends with the grid nodes flagged in the (ny * nx,) bool
        `nodes`, in grid order (a mesh's vertices: the outline, then grid nodes). Those rows are
        summed by grid rows (the pipeline's layout stage keeps them for the curvatures)."""
        head = len(xy) - int(np.count_nonzero(nodes))
        parts = zip(self._blend(xy[:head], 2), self._grid_blend(grid, nodes, 2), strict=True)
        return tuple(np.concatenate(part) for part in parts)  # type: ignore[return-value]

    @property
    def cells(self) -> Cells:
        return Cells(self.centers, self.radii, self.coef)

    def _grid_blend(self, grid: Grid, nodes: np.ndarray, degree: int):
        """_blend at the grid nodes flagged in the (ny * nx,) bool `nodes`, in grid order."""
        slot = np.full(len(nodes), -1, np.int64)
        flagged = np.flatnonzero(nodes)
        slot[flagged] = np.arange(len(flagged))
        (ny, nx), (ox, oy) = grid.shape, grid.origin
        lattice = Lattice(float(ox), float(oy), float(grid.spacing), int(nx), int(ny))
        sums = _grid_sums(lattice, slot, len(flagged), self.cells, degree)
        # take: numpy's fancy index of the (n, 2) points took 8 times as long (0.07 ms at grid 128)
        return self._finish(grid.points.take(flagged, axis=0), sums, degree)

    def _blend(self, xy: np.ndarray, degree: int):
        """g and, up to `degree` (0, 1 or 2), its gradient and Hessian (empty when not asked)."""
        xy = kernel_array(np.atleast_2d(xy))
        sums = _blend_sums(xy, self.cells, bucket_points(xy), degree)
        return self._finish(xy, sums, degree)

    def _finish(self, xy: np.ndarray, sums: tuple[np.ndarray, ...], degree: int):
        """The quotient rule on the sums, and the far-field fallback where no support reaches."""
        big_d = sums[0]
        g, grad, hess = _quotient_rule(*sums, degree)
        far = big_d <= 0
        if far.any():
            dist, nearest = cKDTree(self.points).query(xy[far])
            g[far] = -dist
            u = (self.points[nearest] - xy[far]) / np.maximum(dist, 1e-300)[:, None]
            if degree >= 1:
                grad[far] = u  # toward the nearest boundary point
            if degree == 2:  # g = −|x − b|: ∇²g = −(I − u uᵀ) / |x − b|
                outer = u[:, :, None] * u[:, None, :]
                hess[far] = -(np.eye(2) - outer) / np.maximum(dist, 1e-300)[:, None, None]
        return g, grad, hess

    def __call__(self, xy: np.ndarray) -> np.ndarray:
        """g at (n, 2) points."""
        return self.evaluate(xy)


# The compiled loops below visit, for each cell, the query buckets its support disc overlaps.
# b(t) vanishes from t = 1 on, so a cell's weight is nonzero only within its radius (eq. 2).


@njit(cache=True, nogil=True)
def _quotient_rule(big_d, big_n, grad_d, grad_n, hess_d, hess_n, degree):
    """g = N / D (eq. 1), ∇g = (∇N − g ∇D) / D and ∇²g = (∇²N − g ∇²D − ∇g ∇Dᵀ − ∇D ∇gᵀ) / D
    where D > 0 (zeros elsewhere), up to `degree`."""
    n = len(big_d)
    g = np.zeros(n)
    n1, n2 = (n if degree >= 1 else 0), (n if degree == 2 else 0)
    grad, hess = np.zeros((n1, 2)), np.zeros((n2, 2, 2))
    for i in range(n):
        d = big_d[i]
        if d <= 0:
            continue
        g[i] = big_n[i] / d
        if degree == 0:
            continue
        gx = (grad_n[i, 0] - g[i] * grad_d[i, 0]) / d
        gy = (grad_n[i, 1] - g[i] * grad_d[i, 1]) / d
        grad[i, 0], grad[i, 1] = gx, gy
        if degree == 1:
            continue
        hess[i, 0, 0] = (hess_n[i, 0] - g[i] * hess_d[i, 0] - 2 * gx * grad_d[i, 0]) / d
        hess[i, 0, 1] = (
            hess_n[i, 1] - g[i] * hess_d[i, 1] - gx * grad_d[i, 1] - grad_d[i, 0] * gy
        ) / d
        hess[i, 1, 0] = hess[i, 0, 1]
        hess[i, 1, 1] = (hess_n[i, 2] - g[i] * hess_d[i, 2] - 2 * gy * grad_d[i, 1]) / d
    return g, grad, hess


@njit(cache=True, nogil=True)
def _zero_sums(n, degree):
    """Sums of zeros for n queries, the derivatives' only up to `degree`."""
    n1, n2 = (n if degree >= 1 else 0), (n if degree == 2 else 0)  # unused sums: empty
    return Sums(
        np.zeros(n), np.zeros(n), np.zeros((n1, 2)), np.zeros((n1, 2)), np.zeros((n2, 3)),
        np.zeros((n2, 3)),
    )  # fmt: skip


@njit(cache=True, nogil=True)
def _cell(cells, c):
    """Cell c of `cells` (a Cells) as one Cell."""
    return Cell(
        cells.centers[c, 0], cells.centers[c, 1], 1.0 / cells.radii[c], cells.coef[c, 0],
        cells.coef[c, 1], cells.coef[c, 2],
    )  # fmt: skip


@njit(cache=True, nogil=True)
def _add_cell(sums, i, x, y, cell, degree):
    """Add one cell's w, w f and (by degree) their derivatives at query i, at (x, y), to D, N,
    ∇D, ∇N, ∇²D and ∇²N (eqs. 1-2)."""
    dx, dy = x - cell.cx, y - cell.cy
    scale = cell.scale
    t = np.sqrt(dx * dx + dy * dy) * scale
    if t < 1 / 3:
        w, slope, curl = 0.75 - 2.25 * t * t, -4.5, 0.0
    else:
        w, slope, curl = 1.125 * (t - 1) ** 2, 2.25 * (t - 1) / t, 2.25 / t**3
    a, b = cell.a, cell.b
    f = a * x + b * y + cell.e
    sums.big_d[i] += w
    sums.big_n[i] += w * f
    if degree == 0:
        return
    slope *= scale * scale  # ∇w = b'(t)/t · scale² · d
    wx, wy = slope * dx, slope * dy
    grad_d, grad_n = sums.grad_d, sums.grad_n
    grad_d[i, 0] += wx
    grad_d[i, 1] += wy
    grad_n[i, 0] += wx * f + w * a
    grad_n[i, 1] += wy * f + w * b
    if degree == 1:
        return
    # ∇²w = b'(t)/t · scale² I + (d/dt (b'(t)/t)) / t · scale⁴ d dᵀ
    curl *= scale**4
    hxx, hxy, hyy = slope + curl * dx * dx, curl * dx * dy, slope + curl * dy * dy
    hess_d, hess_n = sums.hess_d, sums.hess_n
    hess_d[i, 0] += hxx
    hess_d[i, 1] += hxy
    hess_d[i, 2] += hyy
    hess_n[i, 0] += hxx * f + 2 * wx * a  # ∇²(w f) = ∇²w f + ∇w ∇fᵀ + ∇f ∇wᵀ
    hess_n[i, 1] += hxy * f + wx * b + wy * a
    hess_n[i, 2] += hyy * f + 2 * wy * b


@njit(cache=True, nogil=True)
def _blend_sums(xy, cells, b, degree):
    """D = Σ w_i and N = Σ w_i f_i (eq. 1) at every query (bucketed in the Buckets b); with
    degree >= 1 also ∇D and ∇N, with degree 2 also ∇²D and ∇²N (as xx, xy, yy)."""
    sums = _zero_sums(len(xy), degree)
    candidates = np.empty(len(xy), np.int64)
    for c in range(len(cells.centers)):
        cell = _cell(cells, c)
        reach = cells.radii[c]
        count = gather(
            b, cell.cx - reach, cell.cx + reach, cell.cy - reach, cell.cy + reach, candidates
        )
        for s in range(count):
            i = candidates[s]
            dx, dy = xy[i, 0] - cell.cx, xy[i, 1] - cell.cy
            if dx * dx + dy * dy >= reach * reach:
                continue
            _add_cell(sums, i, xy[i, 0], xy[i, 1], cell, degree)
    return sums


@njit(cache=True, nogil=True)
def _grid_sums(lattice, slot, n, cells, degree):
    """_blend_sums at the nodes of a Lattice: node (ix, iy) has row slot[iy * nx + ix] among the
    n queries (-1: skipped). Each cell visits, row by row, the nodes within its radius."""
    ox, oy, spacing, nx, ny = lattice
    sums = _zero_sums(n, degree)
    for c in range(len(cells.centers)):
        cell = _cell(cells, c)
        reach = cells.radii[c]
        cx, cy = cell.cx, cell.cy
        y0 = max(math.ceil((cy - reach - oy) / spacing), 0)
        y1 = min(math.floor((cy + reach - oy) / spacing), ny - 1)
        for iy in range(y0, y1 + 1):
            y = oy + spacing * iy
            dy = y - cy
            half = np.sqrt(max(reach * reach - dy * dy, 0.0))
            x0 = max(math.floor((cx - half - ox) / spacing), 0)
            x1 = min(math.ceil((cx + half - ox) / spacing), nx - 1)
            for ix in range(x0, x1 + 1):
                i = slot[iy * nx + ix]
                if i < 0:
                    continue
                x = ox + spacing * ix
                dx = x - cx
                if dx * dx + dy * dy >= reach * reach:
                    continue
                _add_cell(sums, i, x, y, cell, degree)
    return sums


@njit(cache=True, nogil=True)
def _ball_radii(points, centers, radius, b):
    """(m,) each cell's ball radius, `radius` unless its ball holds fewer than N_MIN points,
    then grown to hold them (1.0001 times its N_MIN-th nearest point's distance), and (m,) bool:
    the balls grown. Compiled whole, the count and the search (and numpy's steps between them:
    build_mpu 1.56 -> 1.40 ms on a flat ovate at grid 128, best of 100, two pairs; the same
    cells to the bit on every gallery form and a drawn leaf)."""
    m = len(centers)
    radii = np.empty(m)
    for c in range(m):  # not np.full: its own compile at the first run
        radii[c] = radius
    counts = _ball_counts(points, centers, radii, b)
    grown = counts < N_MIN
    few = np.flatnonzero(grown)
    if len(few):
        far = np.empty((len(few), 2))
        for s in range(len(few)):
            far[s, 0], far[s, 1] = centers[few[s], 0], centers[few[s], 1]
        reach = kth_distances(points, far, N_MIN, b)
        for s in range(len(few)):
            radii[few[s]] = max(radii[few[s]], reach[s] * 1.0001)
    return radii, grown


@njit(cache=True, nogil=True)
def _ball_counts(points, centers, radii, b):
    """(m,) number of points within radii[c] of centers[c] (closed balls)."""
    counts = np.zeros(len(centers), np.int64)
    candidates = np.empty(len(points), np.int64)
    for c in range(len(centers)):
        r = radii[c]
        cx, cy = centers[c, 0], centers[c, 1]
        for s in range(gather(b, cx - r, cx + r, cy - r, cy + r, candidates)):
            i = candidates[s]
            dx, dy = points[i, 0] - cx, points[i, 1] - cy
            if dx * dx + dy * dy <= r * r:
                counts[c] += 1
    return counts


@njit(cache=True, nogil=True)
def _ball_fits(points, normals, centers, radii, b):
    """Per cell, the line through the B-spline-weighted mean of the points in its ball, normal to
    their weighted mean normal; its largest residual and the smallest normal agreement."""
    m = len(centers)
    coef, error, agreement = np.zeros((m, 3)), np.zeros(m), np.empty(m)
    candidates = np.empty(len(points), np.int64)
    for c in range(m):
        agreement[c] = 1.0  # not np.ones: code of its own at the first run's compile
        r = radii[c]
        cx, cy = centers[c, 0], centers[c, 1]
        count = gather(b, cx - r, cx + r, cy - r, cy + r, candidates)
        wsum, px, py, nx_sum, ny_sum = 0.0, 0.0, 0.0, 0.0, 0.0
        for s in range(count):
            i = candidates[s]
            dx, dy = points[i, 0] - cx, points[i, 1] - cy
            d2 = dx * dx + dy * dy
            if d2 > r * r:
                continue
            t = np.sqrt(d2) / r
            w = 1e-3  # points at the rim of a grown ball still count
            if t < 1 / 3:
                w += 0.75 - 2.25 * t * t
            elif t < 1:
                w += 1.125 * (t - 1) ** 2
            wsum += w
            px += w * points[i, 0]
            py += w * points[i, 1]
            nx_sum += w * normals[i, 0]
            ny_sum += w * normals[i, 1]
        if wsum == 0:
            continue
        px, py = px / wsum, py / wsum
        length = max(np.sqrt(nx_sum * nx_sum + ny_sum * ny_sum), 1e-300)
        mx, my = nx_sum / length, ny_sum / length
        # f(x) = n̄ · (p̄ − x): positive on the inner side of the outward normals
        coef[c, 0], coef[c, 1], coef[c, 2] = -mx, -my, mx * px + my * py
        for s in range(count):
            i = candidates[s]
            dx, dy = points[i, 0] - cx, points[i, 1] - cy
            if dx * dx + dy * dy > r * r:
                continue
            residual = abs((points[i, 0] - px) * mx + (points[i, 1] - py) * my)
            error[c] = max(error[c], residual)
            agreement[c] = min(agreement[c], normals[i, 0] * mx + normals[i, 1] * my)
    return coef, error, agreement


QUADRANTS = np.array([[-1, -1], [1, -1], [-1, 1], [1, 1]])  # a split cell's children's offsets


def build_mpu(
    points: np.ndarray,
    normals: np.ndarray,
    tolerance: float,
    inside: Callable[[np.ndarray], np.ndarray],
) -> MPUImplicit:
    """Fit the MPU implicit to oriented boundary points.

    Parameters
    ----------
    points : (n, 2) float array
        Boundary points, in any order.
    normals : (n, 2) float array
        Their unit outward normals.
    tolerance : float
        Largest accepted distance of a cell's points from its fitted line (absolute units).
    inside : callable
        (m, 2) points -> (m,) bool; used only to check the sign of cells far from the boundary,
        whose ball had to grow to reach any point.

    Returns
    -------
    MPUImplicit
    """
    buckets = bucket_points(points)
    # (numpy's min(axis=0) and max: 0.05 ms at a flat ovate's outline at grid 128, bounds 0.002)
    lo, hi = bounds(points, lambda p: (p.min(axis=0), p.max(axis=0)))
    half = 0.6 * float((hi - lo).max())
    spacing = median(neighbour_distances(points, np.arange(len(points))))
    centers = ((lo + hi) / 2)[None, :]
    kept: list[tuple[np.ndarray, ...]] = []
    depth = 0
    second_try = np.zeros(1, dtype=bool)  # the cell's parent was split to mend its sign
    while len(centers):
        radius = float(ALPHA * 2 * np.sqrt(2) * half)
        radii, grown = _ball_radii(points, centers, radius, buckets)
        coef, error, agreement = _ball_fits(points, normals, centers, radii, buckets)
        bad = (error > tolerance) | (agreement < MIN_NORMAL_AGREEMENT)
        wrong_sign = np.zeros(len(centers), dtype=bool)
        if grown.any():  # a far cell's line must give its own centre the right sign
            f_center = np.einsum("ij,ij->i", centers, coef[:, :2]) + coef[:, 2]
            wrong_sign[grown] = (f_center[grown] > 0) != inside(centers.compress(grown, axis=0))
        # A cell smaller than the local point spacing (its ball had to grow) is as fine as the
        # data allows: it is split again only to mend a wrong sign, once. Its children's balls
        # grow to much the same points (beyond a sharp tip, all of them on one side of its
        # centre), so more splits rarely mend it and multiplied such cells by thousands.
        mend = wrong_sign & ~second_try
        split = (depth < MAX_DEPTH) & (half > 0.5 * spacing) & ((bad & ~grown) | mend)
        keep = ~split
        fix = keep & wrong_sign  # could not be split: a constant of the right sign instead
        if fix.any():
            dist = cKDTree(points).query(centers[fix])[0]  # rare: built only then
            signed = np.where(inside(centers[fix]), dist, -dist)
            coef[fix] = np.column_stack([np.zeros((fix.sum(), 2)), signed])
        # compress, not a mask's fancy index of the (m, 2) and (m, 3) rows, and the quadrants'
        # offsets made once: these lines 24 -> 14 us a level of 300 cells, nine levels on a flat
        # ovate at grid 128 (/work/notes/cpu39/micro_mpu_loop.py; the same arrays)
        rows = (centers.compress(keep, axis=0), radii[keep], coef.compress(keep, axis=0))
        kept.append((*rows, np.full(len(rows[1]), depth)))
        half /= 2
        offsets = QUADRANTS * half
        centers = (centers.compress(split, axis=0)[:, None, :] + offsets[None]).reshape(-1, 2)
        second_try = np.repeat(mend[split], 4)
        depth += 1
    c, r, k, d = (np.concatenate(parts) for parts in zip(*kept, strict=True))
    return MPUImplicit(centers=c, radii=r, coef=k, points=points, depth=d.astype(int))
