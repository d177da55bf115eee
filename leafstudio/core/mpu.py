"""Step 2: the 2D multi-level partition-of-unity implicit g(x) of section 3.2 (Ohtake et al.).

g(x) = Σ w_i(x) f_i(x) / Σ w_i(x)                                    (eq. 1)

Each f_i is a linear function fitted to the oriented boundary points inside a ball around the
centre of one adaptive quadtree cell; the cell is split until the fit is within the tolerance.
w_i(x) = b(3|x − c_i| / (2 r_i)) is the quadratic B-spline of eq. 2, so g is C1 everywhere.
g > 0 inside the leaf, g = 0 on its margin, g < 0 outside; near the margin g is close to the
signed distance, because each f_i has a unit gradient.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

ALPHA = 0.75  # support radius = ALPHA * cell diagonal (Ohtake et al.)
N_MIN = 6  # a ball grows until it holds this many points
MIN_NORMAL_AGREEMENT = 0.5  # cos of the largest angle between a cell's normals and their mean
MAX_DEPTH = 12


def bspline_weight(t: np.ndarray) -> np.ndarray:
    """The weight b(t) of eq. 2: 3/4 at t = 0, 0 from t = 1 on, C1 in between."""
    t = np.abs(t)
    return np.where(t < 1 / 3, 0.75 - 2.25 * t**2, np.where(t < 1, 1.125 * (t - 1) ** 2, 0.0))


def _bspline_slope_over_t(t: np.ndarray) -> np.ndarray:
    """b'(t) / t, finite at t = 0 (for the gradient of w)."""
    t = np.abs(t)
    safe = np.where(t > 0, t, 1.0)
    return np.where(t < 1 / 3, -4.5, np.where(t < 1, 2.25 * (t - 1) / safe, 0.0))


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

    def _pairs(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(query index, cell index) for every query point inside a cell's support."""
        hits = cKDTree(xy).query_ball_point(self.centers, self.radii, return_sorted=False)
        counts = np.fromiter((len(h) for h in hits), dtype=np.int64, count=len(hits))
        cells = np.repeat(np.arange(len(hits)), counts)
        queries = np.fromiter((i for h in hits for i in h), dtype=np.int64, count=counts.sum())
        return queries, cells

    def evaluate(self, xy: np.ndarray, gradient: bool = False):
        """g at (n, 2) points; with `gradient`, also its (n, 2) gradient.

        Outside every support (far from the leaf) g is minus the distance to the nearest
        boundary point, and the gradient points toward it.
        """
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        n = len(xy)
        q, c = self._pairs(xy)
        d = xy[q] - self.centers[c]
        scale = 1.5 / self.radii[c]
        t = np.linalg.norm(d, axis=1) * scale
        w = bspline_weight(t)
        f = np.einsum("ij,ij->i", xy[q], self.coef[c, :2]) + self.coef[c, 2]
        weight_sum = np.bincount(q, w, minlength=n)
        value_sum = np.bincount(q, w * f, minlength=n)
        covered = weight_sum > 0
        g = np.empty(n)
        g[covered] = value_sum[covered] / weight_sum[covered]
        far = ~covered
        grad = np.zeros((n, 2))
        if far.any():
            dist, nearest = cKDTree(self.points).query(xy[far])
            g[far] = -dist
            towards = self.points[nearest] - xy[far]
            grad[far] = towards / np.maximum(dist, 1e-300)[:, None]
        if not gradient:
            return g
        dw = (_bspline_slope_over_t(t) * scale**2)[:, None] * d  # ∇w_i
        grad_w = np.column_stack([np.bincount(q, dw[:, k], minlength=n) for k in range(2)])
        grad_f = np.column_stack(
            [np.bincount(q, dw[:, k] * f + w * self.coef[c, k], minlength=n) for k in range(2)]
        )
        ws = weight_sum[covered, None]
        grad[covered] = (grad_f[covered] * ws - value_sum[covered, None] * grad_w[covered]) / ws**2
        return g, grad

    def __call__(self, xy: np.ndarray) -> np.ndarray:
        """g at (n, 2) points."""
        return self.evaluate(xy)


def _fit_cells(
    centers: np.ndarray,
    radii: np.ndarray,
    tree: cKDTree,
    points: np.ndarray,
    normals: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Linear fits for a batch of cells: coef (m, 3), error (m,), normal agreement (m,), radii."""
    counts = tree.query_ball_point(centers, radii, return_length=True)
    few = counts < N_MIN
    if few.any():  # grow the ball until it holds N_MIN points
        dist, _ = tree.query(centers[few], k=N_MIN)
        radii = radii.copy()
        radii[few] = np.maximum(radii[few], dist[:, -1] * 1.0001)
    hits = tree.query_ball_point(centers, radii, return_sorted=False)
    counts = np.fromiter((len(h) for h in hits), dtype=np.int64, count=len(hits))
    cell = np.repeat(np.arange(len(hits)), counts)
    pid = np.fromiter((i for h in hits for i in h), dtype=np.int64, count=counts.sum())
    m = len(centers)
    w = bspline_weight(np.linalg.norm(points[pid] - centers[cell], axis=1) * 1.5 / radii[cell])
    w = w + 1e-3  # points at the rim of a grown ball still count
    wsum = np.bincount(cell, w, minlength=m)
    mean_p = np.column_stack([np.bincount(cell, w * points[pid, k], minlength=m) for k in (0, 1)])
    mean_p /= wsum[:, None]
    sum_n = np.column_stack([np.bincount(cell, w * normals[pid, k], minlength=m) for k in (0, 1)])
    length = np.linalg.norm(sum_n, axis=1)
    mean_n = sum_n / np.maximum(length, 1e-300)[:, None]
    # f(x) = n̄ · (p̄ − x): positive on the inner side of the outward normals
    coef = np.column_stack([-mean_n, np.einsum("ij,ij->i", mean_n, mean_p)])
    residual = np.abs(np.einsum("ij,ij->i", points[pid] - mean_p[cell], mean_n[cell]))
    error = np.zeros(m)
    np.maximum.at(error, cell, residual)
    agreement = np.full(m, 1.0)
    np.minimum.at(agreement, cell, np.einsum("ij,ij->i", normals[pid], mean_n[cell]))
    return coef, error, agreement, radii


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
    tree = cKDTree(points)
    lo, hi = points.min(axis=0), points.max(axis=0)
    half = 0.6 * float((hi - lo).max())
    spacing = float(np.median(tree.query(points, k=2)[0][:, 1]))
    centers = ((lo + hi) / 2)[None, :]
    kept: list[tuple[np.ndarray, ...]] = []
    depth = 0
    while len(centers):
        radii = np.full(len(centers), ALPHA * 2 * np.sqrt(2) * half)
        grown = tree.query_ball_point(centers, radii, return_length=True) < N_MIN
        coef, error, agreement, radii = _fit_cells(centers, radii, tree, points, normals)
        bad = (error > tolerance) | (agreement < MIN_NORMAL_AGREEMENT)
        wrong_sign = np.zeros(len(centers), dtype=bool)
        if grown.any():  # a far cell's line must give its own centre the right sign
            f_center = np.einsum("ij,ij->i", centers, coef[:, :2]) + coef[:, 2]
            wrong_sign[grown] = (f_center[grown] > 0) != inside(centers[grown])
        # A cell smaller than the local point spacing (its ball had to grow) is as fine as the
        # data allows: it is split again only to mend a wrong sign.
        split = (depth < MAX_DEPTH) & (half > 0.5 * spacing) & ((bad & ~grown) | wrong_sign)
        keep = ~split
        fix = keep & wrong_sign  # could not be split: a constant of the right sign instead
        if fix.any():
            dist = tree.query(centers[fix])[0]
            signed = np.where(inside(centers[fix]), dist, -dist)
            coef[fix] = np.column_stack([np.zeros((fix.sum(), 2)), signed])
        kept.append((centers[keep], radii[keep], coef[keep], np.full(keep.sum(), depth)))
        half /= 2
        offsets = np.array([[-1, -1], [1, -1], [-1, 1], [1, 1]]) * half
        centers = (centers[split][:, None, :] + offsets[None]).reshape(-1, 2)
        depth += 1
    c, r, k, d = (np.concatenate(parts) for parts in zip(*kept, strict=True))
    return MPUImplicit(centers=c, radii=r, coef=k, points=points, depth=d.astype(int))
