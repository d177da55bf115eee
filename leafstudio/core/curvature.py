"""Section 4's differentials, curvature of the leaf: closed-form derivatives of z(x) = T(g/δ)·M(x)
and of its graph.

The paper's point is a differentiable surface (section 4: "using differentials as curvatures").
Everything here is exact calculus on the fitted functions, no mesh-based estimates:

- the MPU implicit g = N / D with N = Σ w_i f_i, D = Σ w_i (eq. 1), f_i linear and w_i the
  quadratic B-spline of t = |x − c_i| / r_i (eq. 2; see mpu.py), so
  ∇²g = (∇²N − g ∇²D − ∇g ∇Dᵀ − ∇D ∇gᵀ) / D;
- the taper T(s) = tanh(s), T' = 1 − T², T'' = −2 T T';
- the mixture's Hessian (Mixture.derivatives).

The graph (x, y, z(x, y)) with p = z_x, q = z_y, W = 1 + p² + q² has (upward normal (−p, −q, 1))

    K = (z_xx z_yy − z_xy²) / W²
    H = ((1 + q²) z_xx − 2 p q z_xy + (1 + p²) z_yy) / (2 W^{3/2})
    k1, k2 = H ± √(H² − K)

so a dome (a vein ridge seen from above) has H < 0. The plane frame is orthonormal, so these are
the curvatures of the leaf in world units as well.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from leafstudio.core.buckets import frozen_array, kernel_array
from leafstudio.core.jit import njit
from leafstudio.core.mpu import MPUImplicit
from leafstudio.core.trianglemesh import CURVATURE_ARRAYS


class Differentiable(Protocol):
    """A height function of plane points with closed-form derivatives."""

    def derivatives(
        self, xy: np.ndarray, margin: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Value (n,), gradient (n, 2) and Hessian (n, 2, 2) at (n, 2) points; where the (n,) bool
        `margin` is set, the limits from inside the leaf."""
        ...


def implicit_derivatives(
    implicit: MPUImplicit, xy: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """g, ∇g and ∇²g of the MPU implicit at (n, 2) points, in closed form.

    ∇²g = (∇²N − g ∇²D − ∇g ∇Dᵀ − ∇D ∇gᵀ) / D, summed over the cells in one compiled pass (see
    MPUImplicit.derivatives).

    Returns
    -------
    g : (n,) float array
    gradient : (n, 2) float array
    hessian : (n, 2, 2) float array
        Piecewise: the B-splines are C1, so ∇²g jumps where a point crosses t = 1/3 or t = 1 of
        some cell. Far from the leaf (no support covers the point) g is minus the distance to the
        nearest boundary point and the Hessian is that of −|x − b|.
    """
    return implicit.derivatives(xy)


def taper_derivatives(
    g: np.ndarray,
    grad_g: np.ndarray,
    hess_g: np.ndarray,
    delta: float,
    margin: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """T(g/δ) = tanh(max(g, 0)/δ), its gradient (n, 2) and Hessian (n, 2, 2) by the chain rule.

    T has a kink at g = 0 (flat outside, slope 1/δ inside). Points flagged in the (n,) bool
    `margin` lie on the leaf's edge: they get g = 0 and the limits from inside, which is what a
    mesh of the leaf region sees there.
    """
    g = frozen_array(g)  # the MPU's kept derivatives are read-only: no copies
    margin = np.zeros(len(g), np.bool_) if margin is None else kernel_array(margin, np.bool_)
    return _taper(g, frozen_array(grad_g), frozen_array(hess_g), float(delta), margin)


@njit(cache=True, nogil=True)
def _taper(g, grad_g, hess_g, delta, margin):
    n = len(g)
    t, grad, hess = np.empty(n), np.empty((n, 2)), np.empty((n, 2, 2))
    for i in range(n):
        gi = 0.0 if margin[i] else g[i]
        t[i] = np.tanh(max(gi, 0.0) / delta)
        slope = 1 - t[i] * t[i] if (gi > 0 or margin[i]) else 0.0
        a, b = slope / delta, -2 * t[i] * slope / (delta * delta)
        for r in range(2):
            grad[i, r] = a * grad_g[i, r]
            for c in range(2):
                hess[i, r, c] = b * grad_g[i, r] * grad_g[i, c] + a * hess_g[i, r, c]
    return t, grad, hess


def product_derivatives(
    a: tuple[np.ndarray, np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray, np.ndarray]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Value, gradient and Hessian of the product of two functions given theirs."""
    return _product(*(kernel_array(x) for x in a), *(kernel_array(x) for x in b))


@njit(cache=True, nogil=True)
def _product(va, ga, ha, vb, gb, hb):
    n = len(va)
    value, grad, hess = np.empty(n), np.empty((n, 2)), np.empty((n, 2, 2))
    for i in range(n):
        value[i] = va[i] * vb[i]
        for r in range(2):
            grad[i, r] = ga[i, r] * vb[i] + va[i] * gb[i, r]
            for c in range(2):
                cross = ga[i, r] * gb[i, c] + ga[i, c] * gb[i, r]
                hess[i, r, c] = ha[i, r, c] * vb[i] + va[i] * hb[i, r, c] + cross
    return value, grad, hess


def graph_curvatures(gradient: np.ndarray, hessian: np.ndarray) -> dict[str, np.ndarray]:
    """Mean, Gaussian and principal curvatures of the graph of z from ∇z (n, 2) and ∇²z (n, 2, 2).

    Returns a dict of (n,) arrays named as in CURVATURE_ARRAYS; k1 >= k2.
    """
    names = CURVATURE_ARRAYS
    return dict(zip(names, _graph(kernel_array(gradient), kernel_array(hessian)), strict=True))


@njit(cache=True, nogil=True)
def _graph(gradient, hessian):
    n = len(gradient)
    mean, gauss, k1, k2 = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        p, q = gradient[i, 0], gradient[i, 1]
        zxx, zxy, zyy = hessian[i, 0, 0], hessian[i, 0, 1], hessian[i, 1, 1]
        w = 1 + p * p + q * q
        gauss[i] = (zxx * zyy - zxy * zxy) / (w * w)
        mean[i] = ((1 + q * q) * zxx - 2 * p * q * zxy + (1 + p * p) * zyy) / (2 * w * np.sqrt(w))
        spread = np.sqrt(max(mean[i] * mean[i] - gauss[i], 0.0))
        k1[i], k2[i] = mean[i] + spread, mean[i] - spread
    return mean, gauss, k1, k2


def surface_curvatures(
    surface: Differentiable, xy: np.ndarray, margin: np.ndarray | None = None
) -> dict[str, np.ndarray]:
    """Curvatures (see graph_curvatures) of a height surface at (n, 2) plane points; `margin`
    (n,) bool flags points on the leaf's edge (limits from inside)."""
    _, grad, hess = surface.derivatives(np.atleast_2d(np.asarray(xy, dtype=float)), margin)
    return graph_curvatures(grad, hess)
