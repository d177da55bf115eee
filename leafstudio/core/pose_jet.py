"""A pose's jets (bend.Pose.carry_jet): a flat blade point with its first and second derivatives
carried through the roll, the fold, the twist and the curl in closed form, the chain rule
written out for each point in one compiled kernel.

Each stage was a numpy map over the points with its (n, 3, 3) Jacobian and (n, 3, 3, 3) second
derivatives built whole and pushed by a kernel (bent_curvature's `_chain`, gone with it): 4.7 ms
for the 7,500 vertices of an ovate form's grid-128 mesh posed with all four terms, 1.7 ms of it
the fold about its hinge; 1.1 ms here, the hinge's and the sheet's splines evaluated in the
kernel too. The maps are those of bend.py's `_wrapped` (a roll's cross-section or a curl's midrib
laid on its circle), hinge_fold.HingeFold's `folded` (about a relief's hinge) or the fold
without a relief (y -> y cos, z += |y| tan), and bend.py's `_turned`; each stage's round-off
test (a height or a y within ROUND_OFF of the points' largest coordinate is 0) looks at every
point as that stage takes them, as the numpy stages did. The bent curvatures are those of the
numpy stages to 1e-14 of their largest.
"""

from __future__ import annotations

import numpy as np

from leafstudio.core.jit import njit

PLAIN, HINGE = 1, 2  # a fold without a relief (lifted straight up), and about its hinge


@njit(cache=True, nogil=True)
def _largest(points: np.ndarray) -> float:
    """The points' largest coordinate, in size (0 for none)."""
    top = 0.0
    for i in range(points.shape[0]):
        for a in range(3):
            top = max(top, abs(points[i, a]))
    return top


@njit(cache=True, nogil=True)
def _form(haa: float, hab: float, hbb: float, pa: float, pb: float, qa: float, qb: float) -> float:
    """A symmetric 2 × 2 form [[haa, hab], [hab, hbb]] of the vectors (pa, pb) and (qa, qb)."""
    return haa * pa * qa + hab * (pa * qb + pb * qa) + hbb * pb * qb


@njit(cache=True, nogil=True)
def _plane(
    d: np.ndarray, a: int, b: int, jaa: float, jab: float, jba: float, jbb: float,
    haaa: float, haab: float, habb: float, hbaa: float, hbab: float, hbbb: float,
) -> None:  # fmt: skip
    """One point's (5, 3) derivatives `d` carried by a map of its coordinates a and b alone
    (the third kept), from the map's Jacobian there and its second derivatives (h_xuv =
    ∂²f_x / ∂u ∂v, the same for v u), in place: J ∂ for each, and + H[∂p, ∂q] for the second
    ones (scalars, not arrays: an array a point took 3 times as long)."""
    ua, ub, va, vb = d[0, a], d[0, b], d[1, a], d[1, b]
    uua, uub = _form(haaa, haab, habb, ua, ub, ua, ub), _form(hbaa, hbab, hbbb, ua, ub, ua, ub)
    uva, uvb = _form(haaa, haab, habb, ua, ub, va, vb), _form(hbaa, hbab, hbbb, ua, ub, va, vb)
    vva, vvb = _form(haaa, haab, habb, va, vb, va, vb), _form(hbaa, hbab, hbbb, va, vb, va, vb)
    for k in range(5):
        da, db = d[k, a], d[k, b]
        d[k, a], d[k, b] = jaa * da + jab * db, jba * da + jbb * db
    d[2, a] += uua
    d[2, b] += uub
    d[3, a] += uva
    d[3, b] += uvb
    d[4, a] += vva
    d[4, b] += vvb


@njit(cache=True, nogil=True)
def _shift(points: np.ndarray, d: np.ndarray, profile: np.ndarray, sign: float) -> None:
    """The points' heights raised by sign · a profile of x (its height, first and second
    derivatives at each point: (3, n); the height alone, (1, n), for points without their
    derivatives, `d` empty), with their derivatives, in place."""
    for i in range(points.shape[0]):
        points[i, 2] += sign * profile[0, i]
        if not d.shape[0]:
            continue
        slope, bend = sign * profile[1, i], sign * profile[2, i]
        xu, xv = d[i, 0, 0], d[i, 1, 0]
        for k in range(5):
            d[i, k, 2] += slope * d[i, k, 0]
        d[i, 2, 2] += bend * xu * xu
        d[i, 3, 2] += bend * xu * xv
        d[i, 4, 2] += bend * xv * xv


@njit(cache=True, nogil=True)
def _wrap(points: np.ndarray, d: np.ndarray, a: int, k: float, round_off: float) -> None:
    """bend._wrapped of coordinate a and the height on the points, with their derivatives, in
    place: the radius ρ = R(h k) / k (R bend._rolled_radius, C¹ only at h = 0; the angle's clip
    at half a turn taken from inside). A height within round-off of 0 (a margin's) is taken as
    just above it, on the relief's side, whatever the leaf's size and the sign of k (of a jet;
    points alone, `d` empty, are bent as bend._wrapped bends them)."""
    level = round_off * _largest(points) if d.shape[0] else -1.0
    for i in range(points.shape[0]):
        t = points[i, 2] * k
        angle = min(max(points[i, a] * k, -np.pi), np.pi)
        s, c = np.sin(angle), np.cos(angle)
        outward = k < 0 if abs(points[i, 2]) <= level else t < 0
        inward = np.exp(-max(t, 0.0))
        ratio, rho1, rho2 = (1 - t, -1.0, 0.0) if outward else (inward, -inward, k * inward)
        points[i, a], points[i, 2] = s * ratio / k, 1.0 / k - c * ratio / k
        if not d.shape[0]:
            continue
        _plane(
            d[i], a, 2, c * ratio, s * rho1, s * ratio, -c * rho1,
            -k * (s * ratio), k * c * rho1, s * rho2, k * (c * ratio), k * s * rho1, -c * rho2,
        )  # fmt: skip


@njit(cache=True, nogil=True)
def _fold_plain(
    points: np.ndarray, d: np.ndarray, c: float, s: float, tan: float, round_off: float
) -> None:
    """The fold without a relief (y -> y c, z += |y c| tan: linear each side of the crease;
    a point on it, within round-off, takes the + side's), in place."""
    crease = round_off * _largest(points) if d.shape[0] else 0.0
    for i in range(points.shape[0]):
        side = -1.0 if points[i, 1] < -crease else 1.0
        points[i, 1] *= c
        points[i, 2] += abs(points[i, 1]) * tan
        if d.shape[0]:
            _plane(d[i], 1, 2, c, 0.0, side * s, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@njit(cache=True, nogil=True)
def _fold_hinge(
    points: np.ndarray, d: np.ndarray, c: float, s: float, share: float, band: float,
    round_off: float,
) -> None:  # fmt: skip
    """HingeFold.folded on the points (their heights over the hinge), with their derivatives
    (σ, σ' and σ'' as HingeFold.side has them), in place; a y within round-off of the crease is
    0."""
    crease = round_off * _largest(points) if d.shape[0] else -1.0  # points alone: as given
    ws, lift = share * s, 1 - share + share * c
    for i in range(points.shape[0]):
        y, off = points[i, 1], points[i, 2]
        y = 0.0 if abs(y) <= crease else y
        t = min(max(y / band, -1.0), 1.0)
        if abs(y) < band:
            sigma, slope, bend = 0.5 * t * (3 - t * t), 1.5 * (1 - t * t) / band, -3 * t / band**2
        else:
            sigma, slope, bend = -1.0 if y < 0 else 1.0, 0.0, 0.0
        points[i, 1] = y * c - sigma * share * s * off
        points[i, 2] = abs(y) * s + lift * off
        if not d.shape[0]:
            continue
        across = -s if y < 0 else s
        _plane(
            d[i], 1, 2, c - slope * ws * off, -sigma * ws, across, lift,
            -bend * ws * off, -slope * ws, 0.0, 0.0, 0.0, 0.0,
        )  # fmt: skip


@njit(cache=True, nogil=True)
def _twist(points: np.ndarray, d: np.ndarray, twist: float) -> None:
    """bend._turned on the points (y and z turned about x by twist · x), with their
    derivatives, in place."""
    for i in range(points.shape[0]):
        angle = twist * points[i, 0]
        c, s = np.cos(angle), np.sin(angle)
        y = c * points[i, 1] - s * points[i, 2]
        z = s * points[i, 1] + c * points[i, 2]
        points[i, 1], points[i, 2] = y, z
        if not d.shape[0]:
            continue
        jy, jz = -twist * z, twist * y  # ∂/∂x of y and z
        hyy, hzz = -twist * (twist * y), -twist * (twist * z)  # ∂²/∂x²
        ux, uy, uz = d[i, 0, 0], d[i, 0, 1], d[i, 0, 2]
        vx, vy, vz = d[i, 1, 0], d[i, 1, 1], d[i, 1, 2]
        # the second derivatives' H[∂p, ∂q]: H_y = [[hyy, -t s, -t c], [-t s, 0, 0], [-t c, 0, 0]]
        # and H_z = [[hzz, t c, -t s], [t c, 0, 0], [-t s, 0, 0]] (t the twist)
        uu = (ux * ux, 2 * ux * uy, 2 * ux * uz)  # x x, x y + y x, x z + z x
        uv = (ux * vx, ux * vy + uy * vx, ux * vz + uz * vx)
        vv = (vx * vx, 2 * vx * vy, 2 * vx * vz)
        ys = (hyy, -twist * s, -twist * c)
        zs = (hzz, twist * c, -twist * s)
        for k in range(5):
            dx, dy, dz = d[i, k, 0], d[i, k, 1], d[i, k, 2]
            d[i, k, 1], d[i, k, 2] = jy * dx + c * dy - s * dz, jz * dx + s * dy + c * dz
        for k, pq in ((2, uu), (3, uv), (4, vv)):
            d[i, k, 1] += ys[0] * pq[0] + ys[1] * pq[1] + ys[2] * pq[2]
            d[i, k, 2] += zs[0] * pq[0] + zs[1] * pq[1] + zs[2] * pq[2]


@njit(cache=True, nogil=True)
def _spline(x: np.ndarray, breaks: np.ndarray, c: np.ndarray, rows: int) -> np.ndarray:
    """(rows, n): a cubic spline's height at (n,) x, with its first and second derivatives for
    `rows` 3, from its pieces (scipy's PPoly: breaks and (4, m) coefficients; past the ends the
    end pieces), each point's piece looked for from the last one's first (a mesh's points come
    nearly in order; CubicSpline's calls took 0.5 ms of 22,000 edges' midpoints, a third of
    their carry)."""
    last = breaks.shape[0] - 2
    out = np.empty((rows, x.shape[0]))
    piece = 0
    for i in range(x.shape[0]):
        t = x[i]
        if not (breaks[piece] <= t < breaks[piece + 1]):  # else by bisection
            low, high = 0, last
            while low < high:  # the last piece whose break is at or below t (0 below them)
                middle = (low + high + 1) // 2
                low, high = (middle, high) if breaks[middle] <= t else (low, middle - 1)
            piece = low
        t -= breaks[piece]
        c0, c1, c2, c3 = c[0, piece], c[1, piece], c[2, piece], c[3, piece]
        out[0, i] = ((c0 * t + c1) * t + c2) * t + c3
        if rows == 3:
            out[1, i] = (3 * c0 * t + 2 * c1) * t + c2
            out[2, i] = 6 * c0 * t + 2 * c1
    return out


@njit(cache=True, nogil=True)
def _rolled(hinge: np.ndarray, sheet: np.ndarray, k: float) -> None:
    """The midrib's height h over the roll's sheet s carried to s + g(h − s) once rolled, with
    its derivatives along x (bend._rolled_rise: g(u) = u below the sheet, (1 − exp(−u k)) / k
    above it), in place."""
    for i in range(hinge.shape[1]):
        u = hinge[0, i] - sheet[0, i]
        t = u * k
        inward = np.exp(-t) if t > 0 else 1.0
        g, g1, g2 = (u, 1.0, 0.0) if t <= 0 else ((1 - inward) / k, inward, -k * inward)
        hinge[0, i] = sheet[0, i] + g
        if hinge.shape[0] == 3:
            du, ddu = hinge[1, i] - sheet[1, i], hinge[2, i] - sheet[2, i]
            hinge[1, i] = sheet[1, i] + g1 * du
            hinge[2, i] = sheet[2, i] + g2 * du * du + g1 * ddu


@njit(cache=True, nogil=True)
def posed_jet(
    points: np.ndarray, d: np.ndarray, roll: float, sheet_x: np.ndarray, sheet_c: np.ndarray,
    fold: int, c: float, s: float, tan: float, share: float, band: float,
    midrib_x: np.ndarray, midrib_c: np.ndarray, twist: float, curl: float, level: float,
    round_off: float, offset: np.ndarray, scale: float,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(n, 3) points and (n, 5, 3) derivatives carried as bend.Pose.carry_jet says: rolled
    (`roll`, about the sheet: the spline of pieces sheet_x, sheet_c over x), folded (`fold`: 0
    none, PLAIN, HINGE about the midrib's spline, rolled; c, s, tan the fold's, share and band
    HingeFold's), twisted, and curled (`curl`, about the height `level`). With `d` empty,
    (0, 5, 3), the points alone as bend.Pose.apply bends them (to its round-off). The points
    at a run's unit size unless `offset` is 0 and `scale` 1 (world = offset + scale · unit,
    prepare/units.py): put in the world, carried, and back, with Units' own sums."""
    points, d = points.copy(), d.copy()
    units = scale != 1.0 or offset[0] != 0.0 or offset[1] != 0.0 or offset[2] != 0.0
    if units:
        _scaled(points, d, offset, scale)
    rows = 3 if d.shape[0] else 1  # the profiles' derivatives for a jet
    x = points[:, 0].copy()  # kept by the roll and the fold: their profiles are taken here
    sheet = _spline(x, sheet_x, sheet_c, rows) if roll != 0 else np.zeros((rows, 0))
    if roll != 0:
        _shift(points, d, sheet, -1.0)
        _wrap(points, d, 1, roll, round_off)
        _shift(points, d, sheet, 1.0)
    if fold == PLAIN:
        _fold_plain(points, d, c, s, tan, round_off)
    elif fold == HINGE:
        hinge = _spline(x, midrib_x, midrib_c, rows)
        if roll != 0:
            _rolled(hinge, sheet, roll)
        _shift(points, d, hinge, -1.0)
        _fold_hinge(points, d, c, s, share, band, round_off)
        _shift(points, d, hinge, 1.0)
    if twist != 0:
        _twist(points, d, twist)
    if curl != 0:
        for i in range(points.shape[0]):
            points[i, 2] -= level
        _wrap(points, d, 0, 2 * curl, round_off)
        for i in range(points.shape[0]):
            points[i, 2] += level
    if units:
        _unscaled(points, d, offset, scale)
    return points, d


@njit(cache=True, nogil=True)
def _scaled(points: np.ndarray, d: np.ndarray, offset: np.ndarray, scale: float) -> None:
    """Units.to_world of the points (scale · p, then + offset) and their derivatives times the
    scale, in place. In numpy around the kernel, a roll's 21,300 edge midpoints at unit size took
    0.73-0.77 ms (sag_splits), in it 0.59-0.61; a four-term pose's 7,300 jets 1.61-1.70 and
    1.44-1.53, its 6,900 surface points 0.52-0.57 and 0.41-0.45 (best of 60, alternated)."""
    for i in range(points.shape[0]):
        for k in range(3):
            points[i, k] = scale * points[i, k] + offset[k]
    for i in range(d.shape[0]):
        for j in range(5):
            for k in range(3):
                d[i, j, k] = d[i, j, k] * scale


@njit(cache=True, nogil=True)
def _unscaled(points: np.ndarray, d: np.ndarray, offset: np.ndarray, scale: float) -> None:
    """Units.to_unit of the points ((p − offset) / scale) and their derivatives over the scale,
    in place."""
    for i in range(points.shape[0]):
        for k in range(3):
            points[i, k] = (points[i, k] - offset[k]) / scale
    for i in range(d.shape[0]):
        for j in range(5):
            for k in range(3):
                d[i, j, k] = d[i, j, k] / scale
