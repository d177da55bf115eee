"""Steps 4-5 (sections 3.4-3.5, eq. 8), the leaf's height surface z(x): the scaled GMM, tapered so
that it vanishes on the margin.

A Gaussian mixture never reaches zero, so on its own it cannot pass through the boundary. We
multiply it by a smooth taper of the implicit g:

    z(x) = T(g(x) / δ) · Σ_k a_k N(x | μ_k, Σ_k),     T(s) = tanh(s) for s >= 0

T(0) = 0, so z = 0 exactly where g = 0 (the margin, which lies at height 0 in the plane); T rises
with slope 1 and levels off at 1 deep inside, so the GMM's shape is kept there. g is C1 (MPU's
B-spline weights) and tanh is smooth, so z is C1 everywhere inside and smooth wherever g is C2
(everywhere except on the circles where a cell's support ends). δ is a fraction `taper` of the
leaf's inscribed radius (max g). The amplitudes a_k are fitted by least squares to p(x) over the
inside grid nodes, with the vein points as extra rows so that the surface follows the veins.

A non-planar boundary adds its base surface (base.py): z(x) = b(x) + T(g/δ) Σ a_k N_k(x), where
b passes through the boundary's heights and the mixture fits the veins' relief h_v − b(v'),
signed, so veins below the margin pull the surface under it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from leafstudio.core.base import BaseSurface
from leafstudio.core.buckets import kernel_array
from leafstudio.core.curvature import implicit_derivatives, product_derivatives, taper_derivatives
from leafstudio.core.gmm import Mixture
from leafstudio.core.jit import njit
from leafstudio.core.mpu import MPUImplicit

if TYPE_CHECKING:
    from leafstudio.core.correct import VeinCorrection

Derivatives = tuple[np.ndarray, np.ndarray, np.ndarray]  # f (n,), ∇f (n, 2), ∇²f (n, 2, 2)
VEIN_WEIGHT = 10.0  # the vein rows together weigh this much relative to all grid rows
RIDGE = 1e-10
RELIEF_CAP = 3.0  # a fit target needs Σ a_k N_k at most this many times the veins' relief
REFINE_ROWS = 400  # grid nodes drawn for the refinement, and vein points at most
REFINE_STEPS = 30  # Levenberg-Marquardt iterations at most
UNDERFLOW = 600.0  # exp(-q) for q beyond this is taken as 0 (exactly, not a subnormal)
REFINE_GAIN = 1e-5  # stop once a step lowers the cost by less than this fraction
# the refinement is kept only if its largest misfit at a grid node is at most this many times
# the linear fit's: at K 3-40 on the gallery forms it was 0.30-1.28 times; a spike at K 40-64,
# a component narrowed onto a node or two, 3.6-5.6 times (/work/notes/s27/worst.py)
REFINE_WORST = 2.0


def taper_of(g: np.ndarray, delta: float) -> np.ndarray:
    """T(g / δ) = tanh(g / δ), zero outside the leaf (g < 0)."""
    return np.tanh(np.maximum(g, 0.0) / delta)


def taper_width(taper: float, inside_g: np.ndarray) -> float:
    """δ: `taper` times the leaf's inscribed radius, the largest g at the (n,) nodes inside."""
    return taper * max(float(inside_g.max()), 1e-12)


@dataclass(frozen=True)
class HeightSurface:
    """z(x) = b(x) + T(g(x)/δ) (Σ a_k N_k(x) + c(x)); see the module docstring (b: base.py, or
    0; c: correct.py, or 0)."""

    mixture: Mixture
    implicit: MPUImplicit
    delta: float
    base: BaseSurface | None = None  # the base through a non-planar boundary's heights
    correction: VeinCorrection | None = None  # c(x) onto the veins (correct.py); None: pure GMM

    def relief(self, xy: np.ndarray) -> np.ndarray:
        """Σ a_k N_k(x) + c(x): what the taper multiplies."""
        m = self.mixture.value(xy)
        return m if self.correction is None else m + self.correction.value(xy)

    def _relief_derivatives(
        self, xy: np.ndarray, correction_at: Derivatives | None = None
    ) -> Derivatives:
        m = self.mixture.derivatives(xy)
        if self.correction is None:
            return m
        c = self.correction.derivatives(xy) if correction_at is None else correction_at
        return m[0] + c[0], m[1] + c[1], m[2] + c[2]

    def taper(self, g: np.ndarray) -> np.ndarray:
        """T(g / δ), zero outside the leaf."""
        return taper_of(g, self.delta)

    def __call__(
        self,
        xy: np.ndarray,
        g: np.ndarray | None = None,
        relief: np.ndarray | None = None,
        taper: np.ndarray | None = None,
    ) -> np.ndarray:
        """z at (n, 2) plane points; pass `g` if it is already known there, and `relief`,
        M + c there, too (the surface stage has M at the grid's nodes, and c from the
        correction's lattice: correct.onto_veins), and T(g/δ) there (`taper`)."""
        g = self.implicit(xy) if g is None and taper is None else g
        taper = self.taper(g) if taper is None else taper
        relief = taper * (self.relief(xy) if relief is None else relief)
        return relief if self.base is None else self.base(xy) + relief

    def gradient(self, xy: np.ndarray) -> np.ndarray:
        """(n, 2) ∇z = T'(g/δ) ∇g M / δ + T ∇M, in closed form."""
        g, grad_g = self.implicit.evaluate(xy, gradient=True)
        m, grad_m, _ = self._relief_derivatives(xy)
        t = self.taper(g)
        slope = np.where(g > 0, 1 - t**2, 0.0) / self.delta
        grad = (slope * m)[:, None] * grad_g + t[:, None] * grad_m
        return grad if self.base is None else grad + self.base.derivatives(xy)[1]

    def derivatives(
        self,
        xy: np.ndarray,
        margin: np.ndarray | None = None,
        implicit_at: Derivatives | None = None,
        correction_at: Derivatives | None = None,
    ) -> Derivatives:
        """z (n,), ∇z (n, 2) and ∇²z (n, 2, 2) in closed form (for curvature; see curvature.py).
        Where the (n,) bool `margin` is set, the limits from inside the leaf. `implicit_at`: g,
        ∇g and ∇²g at `xy` when they are known already (the pipeline's layout stage has them at
        the mesh's vertices: they do not change with K); `correction_at`: c, ∇c and ∇²c there
        (the mesh stage's, by differences at its grid nodes: core/node_derivatives.py)."""
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        if implicit_at is None:
            implicit_at = implicit_derivatives(self.implicit, xy)
        taper = taper_derivatives(*implicit_at, self.delta, margin)
        z, grad, hess = product_derivatives(taper, self._relief_derivatives(xy, correction_at))
        if self.base is None:
            return z, grad, hess
        b, grad_b, hess_b = self.base.derivatives(xy)
        return z + b, grad + grad_b, hess + hess_b


def _least_squares_rows(
    surface: HeightSurface,
    inside_xy: np.ndarray,
    inside_g: np.ndarray,
    inside_p: np.ndarray,
    vein_xy: np.ndarray,
    vein_h: np.ndarray,
    vein_g: np.ndarray,
    max_rows: int | None,
    seed: int,
    node_taper: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points, row weights and targets of the fit: grid nodes (p) and vein points (h_v, and g
    there: `vein_g`), at most `max_rows` of each (`node_taper`: T at all the nodes, if known)."""
    if max_rows is not None and len(inside_xy) > max_rows:
        pick = np.random.default_rng(seed).choice(len(inside_xy), max_rows, replace=False)
        inside_xy, inside_g, inside_p = inside_xy[pick], inside_g[pick], inside_p[pick]
        node_taper = None  # tanh of a subset: not read from the whole's (SIMD lanes may differ)
    taper = surface.taper(inside_g) if node_taper is None else node_taper
    xy, weight, target = inside_xy, np.ones(len(inside_xy)), inside_p
    if max_rows is not None and len(vein_xy) > max_rows:  # evenly along the veins
        pick = np.linspace(0, len(vein_xy) - 1, max_rows).astype(np.int64)
        vein_xy, vein_h, vein_g = vein_xy[pick], vein_h[pick], vein_g[pick]
    if len(vein_xy):
        scale = np.sqrt(VEIN_WEIGHT * len(inside_xy) / len(vein_xy))
        xy = np.vstack([xy, vein_xy])
        weight = np.concatenate([weight, np.full(len(vein_xy), scale)])
        target = np.concatenate([target, vein_h])
        taper = np.concatenate([taper, surface.taper(vein_g)])
    # no target above T times RELIEF_CAP times the veins' relief: by a vein raised next to the
    # margin (a basal vein beside a sinus) p rises faster than the taper, and following it took a
    # relief many times the veins' own across the blade (lobes 8 times too high, near vertical)
    cap = RELIEF_CAP * (float(np.abs(vein_h).max()) if len(vein_h) else 0.0) * taper
    target = np.clip(target, -cap, cap)
    return xy, weight * taper, weight * target


def _fit_amplitudes(components: np.ndarray, row_scale: np.ndarray, target: np.ndarray):
    """Linear least squares for a_k (rows already weighted and tapered), from the (n, K)
    components N_k at the rows."""
    rows = row_scale[:, None] * components
    gram = rows.T @ rows
    gram[np.diag_indices_from(gram)] += RIDGE * np.trace(gram) + 1e-300
    return np.linalg.solve(gram, rows.T @ target)


def _kept(
    refined: Mixture, fitted: Mixture, rows: tuple, nodes: int, fitted_value: np.ndarray
) -> tuple[Mixture, np.ndarray]:
    """`refined` if it costs no more than `fitted` over the fit's rows (xy, row scales,
    targets: Σ (s_i z(x_i) − y_i)²) and its largest misfit at one of the first `nodes` rows
    (the grid's) is at most REFINE_WORST times `fitted`'s, else `fitted`; with the kept one's
    Σ a_k N_k at those nodes. Each mixture is read once at the rows, the cost, the misfit and
    the nodes' values from the same reads (read for the cost, again for the misfit, and the
    kept one once more at the nodes by the surface stage: 0.83 ms on a flat ovate at grid 128,
    this 0.35, best of 100; the same figures to the bit). `fitted_value`: `fitted`'s at the
    rows, from the components its amplitudes were fitted with."""
    xy, row_scale, target = rows
    values = [refined.value(xy), fitted_value]
    misfit = [row_scale * v - target for v in values]
    if not float(np.sum(misfit[0] ** 2)) > float(np.sum(misfit[1] ** 2)):
        worst = [np.max(np.abs(m[:nodes]), initial=0.0) for m in misfit]
        if worst[0] <= REFINE_WORST * worst[1]:
            return refined, values[0][:nodes]
    return fitted, values[1][:nodes]


def _pack(mixture: Mixture) -> np.ndarray:
    """Mixture -> parameter vector: per component a, μx, μy, log r11, r21, log r22, with the
    precision Σ⁻¹ = R Rᵀ and R lower triangular (so Σ stays positive definite)."""
    r = np.linalg.cholesky(mixture.precisions)
    return np.column_stack(
        [mixture.amplitudes, mixture.means, np.log(r[:, 0, 0]), r[:, 1, 0], np.log(r[:, 1, 1])]
    ).ravel()


def _unpack(theta: np.ndarray, weights: np.ndarray) -> Mixture:
    t = theta.reshape(-1, 6)
    r = np.zeros((len(t), 2, 2))
    r[:, 0, 0], r[:, 1, 0], r[:, 1, 1] = np.exp(t[:, 3]), t[:, 4], np.exp(t[:, 5])
    covariances = np.linalg.inv(r @ r.transpose(0, 2, 1))
    return Mixture(weights, t[:, 1:3].copy(), covariances, t[:, 0].copy())


def _refine(mixture: Mixture, xy: np.ndarray, row_scale: np.ndarray, target: np.ndarray) -> Mixture:
    """Gauss-Newton (Levenberg-Marquardt) on all of a_k, μ_k, Σ_k so that z follows the targets,
    started from EM's mixture; closed-form Jacobian."""
    xy = kernel_array(xy)
    theta = _levenberg_marquardt(
        xy, kernel_array(row_scale), kernel_array(target),
        _pack(mixture), REFINE_STEPS, REFINE_GAIN,
    )  # fmt: skip
    try:
        refined = _unpack(theta, mixture.weights)
    except np.linalg.LinAlgError:  # a precision factor's diagonal, exp(t), underflowed to 0: a
        return mixture  # singular matrix, raised out of reconstruct as a traceback (a noisy scan)
    if not np.all(np.isfinite(refined.covariances)):
        return mixture
    return refined


@njit(cache=True, nogil=True)
def _residual_rows(xy, row_scale, target, t, jac):
    """Residuals r_i = s_i z(x_i) − y_i (m,) with z = Σ a_k N_k and θ packed as in _pack, and
    their closed-form Jacobian into `jac` (m, 6K) unless it has no rows (the residuals alone).

    In loops, and one signature: an array expression compiles a loop function of its own, and a
    literal True or False as the last argument compiled this kernel twice (1.1 s of CPU at the
    first run, benchmarks/bench_first_run.py --kernels)."""
    k = len(t)
    full = len(jac) > 0
    res = np.empty(len(xy))
    r11, r22, norm = np.empty(k), np.empty(k), np.empty(k)
    for c in range(k):
        r11[c], r22[c] = np.exp(t[c, 3]), np.exp(t[c, 5])
        norm[c] = r11[c] * r22[c] / (2 * np.pi)
    for i in range(len(xy)):
        value = 0.0
        for c in range(k):
            dx, dy = xy[i, 0] - t[c, 1], xy[i, 1] - t[c, 2]
            e1, e2 = r11[c] * dx + t[c, 4] * dy, r22[c] * dy
            q = 0.5 * (e1 * e1 + e2 * e2)
            dens = norm[c] * np.exp(-q) if q < UNDERFLOW else 0.0  # no subnormals: they are slow
            value += t[c, 0] * dens
            if full:
                scaled = row_scale[i] * dens * t[c, 0]  # ∂z/∂log N of this component
                jac[i, 6 * c] = row_scale[i] * dens
                jac[i, 6 * c + 1] = scaled * (r11[c] * e1)
                jac[i, 6 * c + 2] = scaled * (t[c, 4] * e1 + r22[c] * e2)
                jac[i, 6 * c + 3] = scaled * (1 - e1 * r11[c] * dx)
                jac[i, 6 * c + 4] = scaled * (-e1 * dy)
                jac[i, 6 * c + 5] = scaled * (1 - e2 * r22[c] * dy)
        res[i] = row_scale[i] * value - target[i]
    return res


@njit(cache=True, nogil=True)
def _normal_equations(res, jac):
    """|r|² , JᵀJ (p, p) and Jᵀr (p,), in loops: numba's `@` and np.linalg compile its BLAS and
    LAPACK wrappers, about 4 s of CPU at the first run (benchmarks/bench_first_run.py).

    Four rows at a time, each sum still adding row i, then i + 1, ... in turn: every sum is
    read and written once per four rows (612 rows at K 3: 0.034 -> 0.025 ms a call, best of
    200, the same sums to the bit; one row at a time with 1D views before)."""
    m, p = jac.shape
    normal, gradient = np.zeros((p, p)), np.zeros(p)
    cost = 0.0
    i = 0
    while i + 4 <= m:
        r0, r1, r2, r3 = res[i], res[i + 1], res[i + 2], res[i + 3]
        cost = (((cost + r0 * r0) + r1 * r1) + r2 * r2) + r3 * r3
        for a in range(p):
            f0, f1, f2, f3 = jac[i, a], jac[i + 1, a], jac[i + 2, a], jac[i + 3, a]
            gradient[a] = (((gradient[a] + f0 * r0) + f1 * r1) + f2 * r2) + f3 * r3
            for b in range(a + 1):
                normal[a, b] = (
                    ((normal[a, b] + f0 * jac[i, b]) + f1 * jac[i + 1, b]) + f2 * jac[i + 2, b]
                ) + f3 * jac[i + 3, b]
        i += 4
    while i < m:  # the last rows, one at a time
        r = res[i]
        cost += r * r
        for a in range(p):
            factor = jac[i, a]
            gradient[a] += factor * r
            for b in range(a + 1):
                normal[a, b] += factor * jac[i, b]
        i += 1
    for a in range(p):
        for b in range(a):
            normal[b, a] = normal[a, b]
    return cost, normal, gradient


@njit(cache=True, nogil=True)
def _solve_damped(normal, gradient, damping, diag):
    """The step s solving (JᵀJ + damping·diag) s = −Jᵀr by Cholesky (the matrix is symmetric
    positive definite unless singular); None when it is not numerically."""
    p = len(gradient)
    low = np.zeros((p, p))
    for a in range(p):
        for b in range(a + 1):
            total = normal[a, b] + (damping * diag[a] if a == b else 0.0)
            for c in range(b):
                total -= low[a, c] * low[b, c]
            if a == b:
                if not total > 0:  # also NaN
                    return None
                low[a, a] = np.sqrt(total)
            else:
                low[a, b] = total / low[b, b]
    step = np.empty(p)
    for a in range(p):  # L y = −g
        total = -gradient[a]
        for c in range(a):
            total -= low[a, c] * step[c]
        step[a] = total / low[a, a]
    for a in range(p - 1, -1, -1):  # Lᵀ s = y
        total = step[a]
        for c in range(a + 1, p):
            total -= low[c, a] * step[c]
        step[a] = total / low[a, a]
    return step


@njit(cache=True, nogil=True)
def _levenberg_marquardt(xy, row_scale, target, theta, steps, min_gain):
    """Minimise |r(θ)|² (see _residual_rows) from θ in `steps` iterations at most: Marquardt's
    diagonal scaling, Nielsen's damping update, compiled whole (the loop's numpy calls cost more
    than the rows at this size).

    A step is kept only if it lowers the cost, so the result is never worse than the start.
    Stops early once an accepted step gains less than `min_gain` of the cost.
    """
    p = len(theta)
    jac, trial_jac = np.empty((len(xy), p)), np.empty((len(xy), p))
    res = _residual_rows(xy, row_scale, target, theta.reshape(-1, 6), jac)
    cost, normal, gradient = _normal_equations(res, jac)
    largest = 1e-300
    for a in range(p):
        largest = max(largest, normal[a, a])
    damping, growth = 1e-3 * largest, 2.0
    diag = np.empty(p)
    for _ in range(steps):
        top = 0.0
        for a in range(p):
            top = max(top, normal[a, a])
        for a in range(p):
            diag[a] = max(normal[a, a], 1e-12 * top + 1e-300)
        step = _solve_damped(normal, gradient, damping, diag)
        if step is None:  # singular: damp harder
            damping, growth = damping * growth, growth * 2
            continue
        trial = np.empty(p)
        for a in range(p):
            trial[a] = theta[a] + step[a]
        # with its Jacobian: kept, the step needs no second pass over the rows (the rows
        # again at θ: LM 1.92 -> 1.65 ms on a flat ovate at grid 128, best of 60; the same θ)
        trial_res = _residual_rows(xy, row_scale, target, trial.reshape(-1, 6), trial_jac)
        trial_cost = 0.0
        predicted = 0.0
        for i in range(len(trial_res)):
            trial_cost += trial_res[i] * trial_res[i]
        for a in range(p):
            curvature = 0.0
            for b in range(p):
                curvature += normal[a, b] * step[b]
            predicted -= step[a] * (2 * gradient[a] + curvature)
        ratio = (cost - trial_cost) / predicted if predicted > 0 else -1.0
        if not ratio > 0:  # also rejects NaN
            damping, growth = damping * growth, growth * 2
            continue
        gain = cost - trial_cost
        theta = trial
        jac, trial_jac = trial_jac, jac
        cost, normal, gradient = _normal_equations(trial_res, jac)
        damping *= max(1 / 3, 1 - (2 * ratio - 1) ** 3)
        growth = 2.0
        if gain < min_gain * cost:
            break
    return theta


def fit_surface(
    mixture: Mixture,
    implicit: MPUImplicit,
    inside_xy: np.ndarray,
    inside_g: np.ndarray,
    inside_p: np.ndarray,
    vein_xy: np.ndarray,
    vein_h: np.ndarray,
    taper: float,
    refine: bool = True,
    seed: int = 0,
    base: BaseSurface | None = None,
    node_taper: np.ndarray | None = None,
    vein_g: np.ndarray | None = None,
) -> tuple[HeightSurface, np.ndarray]:
    """Fit the amplitudes a_k (and, with `refine`, the means and covariances) so that z follows p
    inside the leaf and h_v on the veins; the surface, and its Σ a_k N_k at the (n,) nodes.

    Parameters
    ----------
    inside_xy, inside_g, inside_p : (n, 2), (n,), (n,) float arrays
        Grid nodes with g >= 0, and g and p there.
    vein_xy, vein_h : (m, 2), (m,) float arrays
        Vein points in the plane and their signed heights.
    taper : float
        δ as a fraction of the inscribed radius max(g).
    refine : bool, default: True
        After the linear fit of the amplitudes, refine every parameter by Levenberg-Marquardt
        (the paper stops after EM; refining brings z several times closer to the veins).
    seed : int, default: 0
        Seed for the choice of grid rows used by the refinement.
    base : BaseSurface, optional
        The base b(x) under a non-planar boundary; p and vein_h are then heights above it.
    node_taper : (n,) float array, optional
        T(g/δ) at the nodes, if the caller has it (the bending stage's: correct.Pinning).
    vein_g : (m,) float array, optional
        g at the vein points, likewise.
    """
    delta = taper_width(taper, inside_g)
    surface = HeightSurface(mixture=mixture, implicit=implicit, delta=delta)
    # g at the veins, once for both fits' rows (read twice, 0.06 ms of a flat ovate's at grid
    # 128; g is read point by point, so a subset's is the same to the bit)
    if vein_g is None:
        vein_g = implicit(vein_xy) if len(vein_xy) else np.zeros(0)
    xy, row_scale, target = _least_squares_rows(
        surface, inside_xy, inside_g, inside_p, vein_xy, vein_h, vein_g, None, seed, node_taper
    )
    # N_k at the rows once, for the amplitudes and the fit's value there (read twice: 0.07 ms
    # of a flat ovate's at grid 128; the same figures to the bit)
    components = mixture.components(xy)
    amplitudes = _fit_amplitudes(components, row_scale, target)
    fitted = Mixture(mixture.weights, mixture.means, mixture.covariances, amplitudes)
    if refine:
        refined = _refine(
            fitted,
            *_least_squares_rows(
                surface, inside_xy, inside_g, inside_p, vein_xy, vein_h, vein_g, REFINE_ROWS, seed
            ),
        )
        # refined on a sample of the rows: kept only if no worse on all of them (over a small
        # blade, K = 7 narrowed a component between the sampled nodes into a spike 11 times
        # the veins' height), and with no node much farther off than before (an ovate at K 48
        # lowered the cost with a spike 4.2 times the veins' height on a node or two)
        rows = (xy, row_scale, target)
        fitted, relief = _kept(refined, fitted, rows, len(inside_xy), components @ amplitudes)
    else:
        relief = fitted.value(inside_xy)
    return HeightSurface(mixture=fitted, implicit=implicit, delta=delta, base=base), relief
