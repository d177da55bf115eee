"""A smooth correction that brings the height surface onto every vein point (issue 21, item 4).

The Gaussian mixture follows the veins only in the least-squares sense: on the gallery's forms
the largest vein-point distance is 0.4-1% of the length, on a drawn leaf with hand-raised veins
0.5% and more, and the curves a designer drew hang in the air. After the mixture is fitted, the
residuals on the veins, r_i = h_i − T(g_i/δ) M(v_i), are taken up by a thin-plate spline c(x)
inside the same taper:

    z(x) = b(x) + T(g(x)/δ) · (Σ_k a_k N_k(x) + c(x)),
    c(x) = Σ_j w_j φ(|x − v_j|) + a₀ + a₁ x + a₂ y,     φ(r) = r² log r.

The thin-plate spline is the interpolant of least bending energy ∫ c_xx² + 2 c_xy² + c_yy², so
it adds no creases of its own (a cubic kernel r³ creased a drawn leaf's margin band 50% more).
T(0) = 0 keeps z = b exactly on the margin. The coefficients solve

    min Σ_i (T_i c(v_i) − r_i)² + λ wᵀ Φ w,

whose normal equations are the rows T_i² (Φ w + P a)_i + λ w_i = T_i r_i and Pᵀ w = 0: where T_i
is 1 this is the usual smoothing spline, and a vein point on or outside the margin (T_i = 0) gets
no weight, so nothing pulls the margin off the boundary. λ is tiny (VEIN_SMOOTHING): it only keeps
the solve well posed when vein points nearly coincide.

Pinned exactly, the spline drew a ridge tight onto a vein wherever the veins stand on a roof (a
form's veins are a quarter of their distance to the margin high: 14° each side of the midrib,
which the mixture rounds 6.5e-3 of the length low). So each value c(v_i) may move within
TOLERANCE / T_i of r_i / T_i to where the spline bends least (`_within`, projected gradient steps
on the bending energy, the factorised system reused): ovate's 99th-percentile interior dihedral
5.0° -> 4.6°, oblong's 6.4° -> 5.8°, every vein point within 1e-3 of the length on the mesh.

The spline's centres are the vein points thinned along each vein (CENTER_STEP), less those of
a later vein within JUNCTION of an earlier one (where a side vein leaves the midrib, the two
disagree by a little within a grid cell, and meeting both bent the surface into a ridge tighter
than a thick solid's sheets can follow), and less the points no smooth correction should chase
(`reachable`).

φ's Hessian has a log r singularity at each centre; ∇²c (curvatures only) cuts the log off at
HESSIAN_CUT of the length, so a mesh vertex that falls on a vein point gets a finite curvature.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg
from numba import njit
from scipy.spatial import cKDTree

from leafstudio.core.buckets import kernel_array
from leafstudio.core.prepare.polygon import thin_curve
from leafstudio.core.surface import HeightSurface

CENTER_STEP = 0.008  # vein points closer than this share of the length are one spline centre
VEIN_SMOOTHING = 1e-9  # λ at unit length (scaled by length²)
BAND = 0.5  # T below this: the margin band, where a vein point close enough is left as it is
CLOSE_ENOUGH = 2e-4  # of the length: a band point this close to the surface needs no pinning
FLAT_SPREAD = 1e-6  # centres spread less than this (of the length) across a line lie on it
HESSIAN_CUT = 1e-3  # ∇²φ's log r is taken as log max(r, this share of the length)
JUNCTION = 0.011  # of the length: a vein's points this near an earlier vein's are left to it
OVERSHOOT = 6.0  # T·c beyond this many times the largest residual is no smooth correction
# (the gallery's forms: 0.96-1.18 times; a drawn leaf with hand-raised veins 4.3; a fan of
# basal veins from a sinus's notch into narrow lobes 17)
TOLERANCE = 4e-4  # of the length: each vein point may stay this far off the surface when that
# lets the spline bend less (_within)
POWER_STEPS = 12
RELAX_STEPS = 40
CHECKED = 2000  # nodes at most where the correction is checked (_tame)
MOST_CENTERS = 800  # beyond this the veins are thinned further: the dense solve grows as its
# cube (3000 centres took seconds a run; the app reruns this on every slider step)


@dataclass(frozen=True)
class VeinCorrection:
    """c(x) = Σ_j w_j φ(|x − v_j|) + a₀ + a₁ x + a₂ y, φ(r) = r² log r: the correction inside
    the taper."""

    centers: np.ndarray  # (m, 2) spline centres on the veins
    weights: np.ndarray  # (m,) w_j
    affine: np.ndarray  # (3,) a₀, a₁, a₂
    log_cut: float  # log of the radius below which ∇²φ's log r is held (HESSIAN_CUT)

    def value(self, xy: np.ndarray) -> np.ndarray:
        """c at (n, 2) plane points."""
        xy = kernel_array(np.atleast_2d(np.asarray(xy, dtype=float)))
        return _spline_value(xy, self.centers, self.weights, self.affine)

    def derivatives(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """c (n,), ∇c (n, 2) and ∇²c (n, 2, 2) in closed form: with d = x − v and r = |d|,
        ∇φ = (2 log r + 1) d and ∇²φ = (2 log r + 1) I + 2 d dᵀ / r² (log r cut off below
        HESSIAN_CUT)."""
        xy = kernel_array(np.atleast_2d(np.asarray(xy, dtype=float)))
        return _spline_derivatives(xy, self.centers, self.weights, self.affine, self.log_cut)


@njit(cache=True, nogil=True)
def _spline_value(xy, centers, weights, affine):
    value = np.empty(len(xy))
    for i in range(len(xy)):
        x, y = xy[i, 0], xy[i, 1]
        v = affine[0] + affine[1] * x + affine[2] * y
        for j in range(len(centers)):
            dx, dy = x - centers[j, 0], y - centers[j, 1]
            r2 = dx * dx + dy * dy
            if r2 > 0.0:
                v += 0.5 * weights[j] * r2 * np.log(r2)
        value[i] = v
    return value


@njit(cache=True, nogil=True)
def _spline_derivatives(xy, centers, weights, affine, log_cut):
    n = len(xy)
    value = np.empty(n)
    grad = np.empty((n, 2))
    hess = np.empty((n, 2, 2))
    for i in range(n):
        x, y = xy[i, 0], xy[i, 1]
        v = affine[0] + affine[1] * x + affine[2] * y
        gx, gy, hxx, hxy, hyy = affine[1], affine[2], 0.0, 0.0, 0.0
        for j in range(len(centers)):
            dx, dy = x - centers[j, 0], y - centers[j, 1]
            r2 = dx * dx + dy * dy
            if r2 == 0.0:
                continue  # φ, ∇φ are 0 at the centre (∇²φ's log is cut off: see below)
            w = weights[j]
            lg = 0.5 * np.log(r2)
            v += w * r2 * lg
            gx += w * dx * (2 * lg + 1)
            gy += w * dy * (2 * lg + 1)
            cut = 2 * max(lg, log_cut) + 1
            hxx += w * (cut + 2 * dx * dx / r2)
            hxy += w * (2 * dx * dy / r2)
            hyy += w * (cut + 2 * dy * dy / r2)
        value[i] = v
        grad[i, 0], grad[i, 1] = gx, gy
        hess[i, 0, 0], hess[i, 0, 1], hess[i, 1, 0], hess[i, 1, 1] = hxx, hxy, hxy, hyy
    return value, grad, hess


def _thin_vein(vein: np.ndarray, step: float) -> np.ndarray:
    """Indices of a vein's (m, 2) points at least `step` apart along it, its end kept in place
    of the point before it when that lies within half a step (two centres a hair apart with
    different residuals take opposite weights of thousands: a spike beside the vein's end)."""
    kept = thin_curve(vein, step, keep_end=True)
    if len(kept) > 2 and np.linalg.norm(vein[kept[-1]] - vein[kept[-2]]) < 0.5 * step:
        kept = np.delete(kept, -2)
    return kept


def spline_centers(veins: list[np.ndarray], length: float) -> list[np.ndarray]:
    """Indices kept of each vein's (m_i, 2) points: at least CENTER_STEP · length apart along it
    (polygon.thin_curve), at most MOST_CENTERS in all, none within JUNCTION · length of an
    earlier vein's."""
    step = CENTER_STEP * length
    kept = [_thin_vein(v, step) for v in veins]
    total = sum(len(k) for k in kept)
    if total > MOST_CENTERS:
        step *= total / MOST_CENTERS
        kept = [_thin_vein(v, step) for v in veins]
    laid = np.zeros((0, 2))
    for i, vein in enumerate(veins):  # at a junction the earlier (longer) vein decides
        if len(laid):
            near = cKDTree(laid).query(vein[kept[i]], distance_upper_bound=JUNCTION * length)[0]
            kept[i] = kept[i][~np.isfinite(near)]
        laid = np.vstack([laid, vein[kept[i]]])
    return kept


def reachable(
    taper: np.ndarray,
    residual: np.ndarray,
    relief: float,
    length: float,
    stretch: np.ndarray | float = 1.0,
) -> np.ndarray:
    """(m,) bool: the vein points the spline is made to pass through.

    Left out: a point that only a correction higher than the veins' own relief could reach
    (|r| > relief · T: a vein raised next to the margin, which z = b there cannot follow without
    a spike), and a point in the margin band (T < BAND) that is already within CLOSE_ENOUGH of the
    length (a thin tip's midrib: pinning it there only sharpens the tip), over its `stretch`
    (onto_veins).
    """
    spike = np.abs(residual) > relief * taper
    settled = (taper < BAND) & (np.abs(residual) <= CLOSE_ENOUGH * length / stretch)
    return (taper > 0) & ~spike & ~settled


def fit_correction(
    centers: np.ndarray,
    taper: np.ndarray,
    residual: np.ndarray,
    length: float,
    stretch: np.ndarray | float = 1.0,
) -> VeinCorrection | None:
    """The spline c with T_i c(v_i) within TOLERANCE of r_i at the vein points (over their
    `stretch`, onto_veins), bending least.

    Parameters
    ----------
    centers : (m, 2) float array
        Vein points in the plane (spline_centers).
    taper : (m,) float array
        T(g/δ) there, in [0, 1].
    residual : (m,) float array
        h_i − T_i M(v_i): what the mixture leaves to correct.
    length : float
        The leaf's length (λ and the Hessian's cut-off scale with it).
    stretch : (m,) float array or float, default 1
        How many times a distance off the surface grows at each point when the blade is bent.

    Returns
    -------
    VeinCorrection, or None when no vein point lies inside the margin.
    """
    inside = taper > 0
    if np.count_nonzero(inside) < 3:
        return None
    d = np.sqrt(((centers[:, None, :] - centers[None, :, :]) ** 2).sum(axis=2))
    phi = np.where(d > 0, d**2 * np.log(np.maximum(d, 1e-300)), 0.0)
    # the linear part along the directions the centres span: a midrib alone is a line, across
    # which a slope would be undetermined (and blow up)
    mean = centers.mean(axis=0)
    _, spread, directions = np.linalg.svd(centers - mean, full_matrices=False)
    spanned = directions[spread > FLAT_SPREAD * length * np.sqrt(len(centers))]
    poly = np.column_stack([np.ones(len(centers)), (centers - mean) @ spanned.T])
    m, q = len(centers), poly.shape[1]
    system = np.zeros((m + q, m + q))
    t2 = taper**2
    system[:m, :m] = t2[:, None] * phi
    system[np.diag_indices(m)] += VEIN_SMOOTHING * length**2
    system[:m, m:] = t2[:, None] * poly
    system[m:, :m] = poly.T
    try:
        factors = scipy.linalg.lu_factor(system, check_finite=False)
    except (np.linalg.LinAlgError, ValueError):
        return None

    def spline_of(values: np.ndarray) -> np.ndarray:  # (w, a) with T_i c(v_i) = T_i values_i
        return scipy.linalg.lu_solve(factors, np.concatenate([t2 * values, np.zeros(q)]))

    target = np.divide(residual, taper, out=np.zeros(m), where=taper > 0)
    slack = TOLERANCE * length / (np.maximum(taper, 1e-3) * stretch)
    solution = spline_of(_within(target, slack, spline_of))
    if not np.all(np.isfinite(solution)):
        return None
    slope = spanned.T @ solution[m + 1 :]  # back to a₀ + a₁ x + a₂ y
    affine = np.array([solution[m] - slope @ mean, *slope])
    return VeinCorrection(
        centers=kernel_array(centers),
        weights=solution[:m].copy(),
        affine=affine,
        log_cut=float(np.log(HESSIAN_CUT * length)),
    )


def _within(
    target: np.ndarray, slack: np.ndarray, spline_of: Callable[[np.ndarray], np.ndarray]
) -> np.ndarray:
    """(m,) values within `slack` of `target` whose spline bends least, nearly: projected
    gradient steps (FISTA) on the bending energy vᵀ K v, whose gradient is the spline's weights
    (`spline_of`, one back-substitution). The stiffest bends go first: a ridge the spline drew
    tight onto a vein (a form's midrib, where side veins stand on a roof 14° each side) is
    widened while every vein point stays within the slack."""

    def weights(values: np.ndarray) -> np.ndarray:
        return spline_of(values)[: len(values)]

    probe = np.random.default_rng(0).standard_normal(len(target))
    for _ in range(POWER_STEPS):  # the largest eigenvalue of K: the step
        probe = weights(probe)
        largest = float(np.linalg.norm(probe))
        if not np.isfinite(largest) or largest == 0:
            return target
        probe /= largest
    lo, hi = target - slack, target + slack
    values = previous = ahead = target
    momentum = 1.0
    for _ in range(RELAX_STEPS):
        values = np.clip(ahead - weights(ahead) / largest, lo, hi)
        following = 0.5 * (1 + np.sqrt(1 + 4 * momentum**2))
        ahead = values + (momentum - 1) / following * (values - previous)
        previous, momentum = values, following
    return values


def onto_veins(
    surface: HeightSurface,
    veins: list[np.ndarray],
    heights: list[np.ndarray],
    length: float,
    nodes: tuple[np.ndarray, np.ndarray] | None = None,
    stretch: list[np.ndarray] | None = None,
) -> HeightSurface:
    """`surface` with a VeinCorrection that brings it onto the vein points.

    Parameters
    ----------
    surface : HeightSurface
        The fitted surface (no correction yet).
    veins, heights : lists of (m_i, 2) and (m_i,) float arrays
        Each vein's points in the plane and their heights above the base.
    length : float
        The leaf's length.
    nodes : ((n, 2), (n,)) float arrays, optional
        Points inside the leaf and T(g/δ) there, where the correction is checked: a correction
        that adds more than OVERSHOOT times the largest residual anywhere is refitted without
        the vein points of the margin band, and dropped if it still does (see `_tame`).
    stretch : list of (m_i,) float arrays, optional
        How many times the leaf's bend lengthens a distance off the blade at each vein point
        (bend.normal_stretch, at least 1): a fold on a rolled tube shears its section, and a
        vein point TOLERANCE off the flat surface stood up to 3.9 times that off the bent mesh.
        Each point's tolerance is divided by it.
    """
    if not veins:
        return surface
    kept = spline_centers(veins, length)
    centers = np.vstack([v[k] for v, k in zip(veins, kept, strict=True)])
    h = np.concatenate([z[k] for z, k in zip(heights, kept, strict=True)])
    taper = surface.taper(surface.implicit(centers))
    residual = h - taper * surface.relief(centers)
    relief = float(np.abs(h).max())
    grows = (
        np.ones(len(h))
        if stretch is None
        else np.concatenate([s[k] for s, k in zip(stretch, kept, strict=True)])
    )
    keep = reachable(taper, residual, relief, length, grows)
    for pinned in (keep, keep & (taper >= BAND)):
        correction = fit_correction(
            centers[pinned], taper[pinned], residual[pinned], length, grows[pinned]
        )
        if correction is None:
            return surface
        if nodes is None or _tame(correction, nodes, np.abs(residual[pinned]).max()):
            return replace(surface, correction=correction)
    return surface


def _tame(correction: VeinCorrection, nodes: tuple[np.ndarray, np.ndarray], largest: float) -> bool:
    """Whether T·c stays within OVERSHOOT times the largest residual it corrects at the nodes.

    Pinned points of the margin band (T small, so c must be r/T there) whose r/T differ a lot
    over a short way (a short basal vein in a narrow lobe, a notch) tilt the spline's affine part
    steeply: a fan of veins from a sinus's notch bent the apex down 25 times the veins' relief,
    for residuals under 1% of the length."""
    xy, taper = nodes
    every = max(1, len(xy) // CHECKED)  # a tilt is as wide as the blade: a sample finds it
    tilt = taper[::every] * correction.value(xy[::every])
    return bool(np.all(np.abs(tilt) <= OVERSHOOT * largest))
