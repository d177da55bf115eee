"""φ = −kei(r/ℓ), the vein correction's kernel (correct.py), and its derivatives: tables and the
compiled kernels that read them.

kei, kei' and ker are tabulated once (scipy.special, KELVIN_STEP apart up to KELVIN_END, past
which φ is taken as 0) and read back by cubic Hermite interpolation.
"""

from __future__ import annotations

import numpy as np
import scipy.special

from leafstudio.core.jit import njit

KELVIN_STEP = 0.005  # of ℓ: the tables' step (a table 16 times finer read 1.5 times slower;
# 0.01: ∇c, read from kei''s own table, stood 8e-6 off a finite difference of c on the nested demo
# at grid 48, with weights up to 1.2 where the values are chosen for the surface's bending,
# tests/core/test_curvature.py; twice as fine, as fast)
KELVIN_END = 16.0  # of ℓ: φ is taken as 0 past this (kei(16) = 3e-6 against kei(0) = −0.79)


def _kelvin_tables() -> np.ndarray:
    """(n, 12): on each interval [ρ_i, ρ_i + KELVIN_STEP], ρ_i = i KELVIN_STEP up to
    KELVIN_END, the cubic Hermite polynomials (coefficients of 1, u, u², u³, u in [0, 1]) of
    kei (slopes kei'), kei' (slopes kei'' = ker − kei'/ρ) and ker (slopes ker'). kei'' and ker
    have a log singularity at ρ = 0: the first interval takes the next node's values there (only
    ρ < KELVIN_STEP reads them, which the Hessian never does)."""
    rho = np.arange(0.0, KELVIN_END + 2 * KELVIN_STEP, KELVIN_STEP)
    inner = rho[1:]
    kei_d = scipy.special.keip(rho)
    ker = np.concatenate([[scipy.special.ker(inner[0])], scipy.special.ker(inner)])
    ker_d = np.concatenate([[scipy.special.kerp(inner[0])], scipy.special.kerp(inner)])
    kei_dd = np.concatenate([[kei_d[1] / KELVIN_STEP], ker[1:] - kei_d[1:] / inner])
    columns = []
    for f, slope in ((scipy.special.kei(rho), kei_d), (kei_d, kei_dd), (ker, ker_d)):
        f0, f1 = f[:-1], f[1:]
        s0, s1 = slope[:-1] * KELVIN_STEP, slope[1:] * KELVIN_STEP
        columns += [f0, s0, 3 * (f1 - f0) - 2 * s0 - s1, 2 * (f0 - f1) + s0 + s1]
    table = np.ascontiguousarray(np.column_stack(columns))
    table[-1] = 0.0  # never an interval read (t < its index): φ = 0 past KELVIN_END, for
    # the kernels that clamp t to it instead of branching (spline_value, phi_matrix,
    # spline_gradient)
    return table


KELVIN = _kelvin_tables()
KEI = np.ascontiguousarray(KELVIN[:, :4])  # kei's polynomials alone, for the kernels that read
# only φ (spline_value, phi_matrix): a row is 32 bytes, not 96 (3.42 ->
# 3.32 ms for 5292 + 1603 points against 200 centres, as a flat ovate at grid 128, best of 60)


def phi_at(rho: np.ndarray) -> np.ndarray:
    """φ = −kei at ρ = r/ℓ (any shape) from the tables, 0 from KELVIN_END on (numpy: the
    solve's (m, m) matrix; the compiled kernels read the same polynomials)."""
    t = rho / KELVIN_STEP
    k = np.minimum(t.astype(np.intp), len(KELVIN) - 1)
    u = t - k
    value = KELVIN[:, 3].take(k)  # column by column: no (..., 4) temporary
    for column in (2, 1, 0):
        value = KELVIN[:, column].take(k) + u * value
    return np.where(t < len(KELVIN) - 1, -value, 0.0)


@njit(cache=True, nogil=True, inline="always")
def read(table, i, column, u):
    """The Hermite polynomial in `column` (0: kei, 4: kei', 8: ker) of interval i at u."""
    return table[i, column] + u * (
        table[i, column + 1] + u * (table[i, column + 2] + u * table[i, column + 3])
    )


@njit(cache=True, nogil=True, inline="always")
def _columns(points):
    """The (m, 2) points' x and y as two contiguous arrays: the kernels' inner loops over the
    centres then load them in vector lanes (from the interleaved pairs they did not)."""
    x, y = np.empty(len(points)), np.empty(len(points))
    for j in range(len(points)):
        x[j], y[j] = points[j, 0], points[j, 1]
    return x, y


@njit(cache=True, nogil=True, inline="always")
def _intervals(x, y, cx, cy, scale, end, rows, at):
    """The table's interval (`rows`) and the place in it (`at`, u in [0, 1)) of every centre
    (cx, cy) from the point (x, y): a loop of arithmetic alone, in vector lanes (t clamped to
    the table's last row, of zeros, rather than branched on)."""
    for j in range(len(cx)):
        dx, dy = x - cx[j], y - cy[j]
        t = min(np.sqrt(dx * dx + dy * dy) * scale, end)
        k = int(t)
        rows[j] = k
        at[j] = t - k


@njit(cache=True, nogil=True, inline="always")
def _weighted_phi(table, weights, rows, at):
    """Σ_j w_j φ at the intervals and places `_intervals` found: one table row read after
    another, in four running sums (not in vector lanes: read in lanes, the rows are gathered,
    and a gather of four doubles took longer than the four reads)."""
    m = len(rows)
    s0, s1, s2, s3 = 0.0, 0.0, 0.0, 0.0
    j = 0
    while j + 4 <= m:
        s0 -= weights[j] * read(table, rows[j], 0, at[j])
        s1 -= weights[j + 1] * read(table, rows[j + 1], 0, at[j + 1])
        s2 -= weights[j + 2] * read(table, rows[j + 2], 0, at[j + 2])
        s3 -= weights[j + 3] * read(table, rows[j + 3], 0, at[j + 3])
        j += 4
    for i in range(j, m):
        s0 -= weights[i] * read(table, rows[i], 0, at[i])
    return (s0 + s1) + (s2 + s3)


@njit(cache=True, nogil=True)
def spline_value(xy, centers, weights, reach, table, step):
    """Σ_j w_j φ(|x_i − v_j|) at each of the (n, 2) points, in two loops a point: the distances
    and table intervals in vector lanes, then the table's rows read one by one (one loop in
    vector lanes, its rows gathered: 2.22 -> 1.68 ms for 5292 nodes and 200 centres, best of
    40, as the nodes off the lattice of a flat ovate at grid 128; the sum in a different order:
    4e-15 of c's largest value apart). The centres' x and y are read from arrays of their own
    (3.0 -> 2.2 ms when in one loop)."""
    cx, cy = _columns(centers)
    value = np.empty(len(xy))
    scale = 1.0 / (reach * step)  # r -> ρ / KELVIN_STEP
    end = float(len(table) - 1)
    rows = np.empty(len(cx), dtype=np.int64)
    at = np.empty(len(cx))
    for i in range(len(xy)):
        _intervals(xy[i, 0], xy[i, 1], cx, cy, scale, end, rows, at)
        value[i] = _weighted_phi(table, weights, rows, at)
    return value


@njit(cache=True, nogil=True)
def phi_matrix(xy, centers, reach, table, step, taper):
    """(n, m) φ(|x_i − v_j|), and T_i φ(|x_i − v_j|) in single precision (bending.py: c on a
    lattice per unit weight, and the gram's factor; numpy's `phi_at` took six times as long, and
    T φ formed after it, 2.6 MB more to allocate on the nested demo at grid 128, as long again).
    In two loops a point as spline_value (in one, in vector lanes: 1.09 -> 0.58 ms for 1603 nodes,
    200 centres, best of 60)."""
    cx, cy = _columns(centers)
    out = np.empty((len(xy), len(centers)))
    tapered = np.empty((len(xy), len(centers)), dtype=np.float32)
    scale = 1.0 / (reach * step)
    end = float(len(table) - 1)
    rows = np.empty(len(cx), dtype=np.int64)
    at = np.empty(len(cx))
    for i in range(len(xy)):
        _intervals(xy[i, 0], xy[i, 1], cx, cy, scale, end, rows, at)
        for j in range(len(cx)):
            value = -read(table, rows[j], 0, at[j])
            out[i, j] = value
            tapered[i, j] = taper[i] * value
    return out, tapered


@njit(cache=True, nogil=True)
def spline_gradient(xy, centers, weights, reach, table, step):
    """c and ∇c at each of the (n, 2) points, without ∇²c (VeinCorrection.value_and_gradient: the
    margin's points, where T = 0 multiplies ∇²c). In two loops a point as spline_value, the
    second reading kei and kei' alone (spline_derivatives at the outline's 502 points against
    200 centres on a flat ovate at grid 128: 0.62 ms; this 0.36, best of 60; c and ∇c 2e-15
    and 1e-15 of their largest apart). The first loop takes each root once for both t and 1/r
    (taken again after _intervals: 0.53 -> 0.44 ms, best of 200, the same values to the bit)."""
    cx, cy = _columns(centers)
    n = len(xy)
    value = np.empty(n)
    grad = np.empty((n, 2))
    scale = 1.0 / (reach * step)
    end = float(len(table) - 1)
    inv_reach = 1.0 / reach
    rows = np.empty(len(cx), dtype=np.int64)
    at = np.empty(len(cx))
    inv_r = np.empty(len(cx))  # 1/(r ℓ): on a centre finite, and ∇φ's d = 0 there
    for i in range(n):
        x, y = xy[i, 0], xy[i, 1]
        for j in range(len(cx)):  # _intervals' loop, with 1/r from the same root
            dx, dy = x - cx[j], y - cy[j]
            r = np.sqrt(dx * dx + dy * dy)
            t = min(r * scale, end)
            k = int(t)
            rows[j] = k
            at[j] = t - k
            inv_r[j] = inv_reach / max(r, 1e-100)
        v, gx, gy = 0.0, 0.0, 0.0
        for j in range(len(cx)):
            k, u, w = rows[j], at[j], weights[j]
            v -= w * read(table, k, 0, u)
            across = -w * read(table, k, 4, u) * inv_r[j]  # w φ'(r)/r, kei'(ρ) read
            gx += across * (x - cx[j])
            gy += across * (y - cy[j])
        value[i] = v
        grad[i, 0], grad[i, 1] = gx, gy
    return value, grad


@njit(cache=True, nogil=True, fastmath=True)
def spline_derivatives(xy, centers, weights, reach, cut, table, step):
    """c, ∇c and ∇²c at each of the (n, 2) points (VeinCorrection.derivatives). The centres
    farther than `cut` (over ℓ) from a point, nearly all, are summed without a branch, t clamped
    to the table's last row (zeros) and in vector lanes; the few nearer, whose Hessian's radial
    parts are read at `cut`, are added after, one by one (the outline's 502 points against 200
    centres on a flat ovate at grid 128: 1.03 -> 0.61 ms, best of 60; a branch per centre kept
    the loop out of vector lanes)."""
    cx, cy = _columns(centers)
    n = len(xy)
    value = np.empty(n)
    grad = np.empty((n, 2))
    hess = np.empty((n, 2, 2))
    scale = 1.0 / (reach * step)
    end = float(len(table) - 1)
    held_t = max(cut / step, 1.0)  # ∇²φ's radial parts are read at t no less than this
    inv_reach = 1.0 / reach
    inv2 = inv_reach * inv_reach
    for i in range(n):
        x, y = xy[i, 0], xy[i, 1]
        v, gx, gy, flat, hxx, hxy, hyy = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        near = 0
        for j in range(len(cx)):
            dx, dy = x - cx[j], y - cy[j]
            r = np.sqrt(dx * dx + dy * dy)
            t = min(r * scale, end)
            near += t < held_t
            w = weights[j]
            k = int(t)
            u = t - k
            v -= w * read(table, k, 0, u)
            inv_r = 1.0 / max(r, 1e-100)  # on a centre: finite, and ∇φ's d = 0 there
            across = -w * read(table, k, 4, u) * inv_r * inv_reach  # w φ'(r)/r, kei'(ρ) read
            gx += across * dx
            gy += across * dy
            far = t >= held_t
            bend = (-w * read(table, k, 8, u) * inv2 - 2.0 * across) * inv_r * inv_r
            flat += across if far else 0.0  # ∇²φ = φ'/r I + (φ'' − φ'/r) d dᵀ/r²
            hxx += bend * dx * dx if far else 0.0
            hxy += bend * dx * dy if far else 0.0
            hyy += bend * dy * dy if far else 0.0
        for j in range(len(cx) if near else 0):  # the centres within `cut`: w (φ'' − φ'/r)
            dx, dy = x - cx[j], y - cy[j]
            r = np.sqrt(dx * dx + dy * dy)
            if r * scale >= held_t:
                continue
            w = weights[j]
            k = int(held_t)
            u = held_t - k
            across = -w * read(table, k, 4, u) / (held_t * step) * inv2
            bend = -w * read(table, k, 8, u) * inv2 - 2.0 * across
            flat += across
            if r > 0.0:
                bend /= r * r
                hxx += bend * dx * dx
                hxy += bend * dx * dy
                hyy += bend * dy * dy
            else:  # on the centre: the mean of the two radial curvatures, either way
                hxx += 0.5 * bend
                hyy += 0.5 * bend
        value[i] = v
        grad[i, 0], grad[i, 1] = gx, gy
        hess[i, 0, 0], hess[i, 1, 1] = flat + hxx, flat + hyy
        hess[i, 0, 1] = hess[i, 1, 0] = hxy
    return value, grad, hess
