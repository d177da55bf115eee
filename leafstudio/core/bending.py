"""The vein correction's values chosen for the whole surface's bending (issue 21, item 4).

correct.py brings the height surface onto the vein points with a spline c, each value c(v_i)
free within a tolerance. Chosen so that c alone bends least (`correct._within`), the surface
through the veins still creased more than the paper's pure GMM surface on some rows of
`bench_bent.py --veins` (99th-percentile dihedral: deltoid's margin band 2.35° against 2.19°, a
drawn leaf's 8.54° against 8.32°, linear's 7.81° against 7.78°): c bent least where the mixture
bent most. Here the values are chosen within the same tolerances so that the surface itself,
z = T · (M + c) over the grid's nodes inside the leaf, bends least: the sum of its squared second
differences (xx, yy and the cross difference) on a lattice of the nodes (`lattice`: finer in
the margin band). c is linear in its values (the spline's weights are one solve of them), so
this is a small quadratic program in the values, box-constrained, solved by projected gradient
steps (FISTA) from the residuals themselves (starting from `_within`'s values changed nothing).
The margin band's 99th-percentile dihedral falls below the paper's surface
on every gallery form (lanceolate 3.17° -> 1.66°, deltoid 2.19° -> 1.98°), and its inside on all
but two (oblanceolate 2.94° against 2.85°; orbicular, whose midrib follows the dip of its base's
flattening, forms/relief.py, 1.30° against 1.08°).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse

LATTICE_NODES = 2500  # grid nodes, about, on the lattice whose bending is summed
FINE = 0.97  # T below this: the margin band, where the lattice is finer (see lattice)
POWER_STEPS = 20  # power steps for the largest eigenvalue of the normal matrix
STEPS = 50  # projected gradient steps (100: the same bench_bent --veins rows, 0.01° apart)


@dataclass(frozen=True)
class Bending:
    """The lattice over which the surface's bending is summed: its nodes, T(g/δ) and the
    mixture's relief M there, and the (r, n) sparse second differences D between them."""

    xy: np.ndarray  # (n, 2) lattice nodes in the plane
    taper: np.ndarray  # (n,) T(g/δ)
    relief: np.ndarray  # (n,) M, the mixture alone
    differences: scipy.sparse.csr_matrix  # (r, n) D, single precision


def lattice(xy: np.ndarray, taper: np.ndarray) -> tuple[np.ndarray, scipy.sparse.csr_matrix]:
    """Indices of the (n, 2) grid nodes `xy` kept on the lattice and the second differences
    between them, (rows, kept) sparse, one row per direction (x, y, and the cross difference)
    wherever all its nodes are kept. In the margin band (T < FINE) the lattice takes every
    stride-th row and column (stride so that about LATTICE_NODES would be kept over the whole
    blade), farther in every second of those: the surface bends most where the taper brings it
    down (a stride of 3 left margin bands rougher than the paper's surface), and the solve's cost
    grows with the nodes."""
    steps = np.abs(np.diff(xy[:, 0]))  # every step between grid nodes is the spacing's multiple
    steps = steps[steps > 0]
    spacing = float(steps.min()) if len(steps) else 1.0
    stride = max(1, round(float(np.sqrt(len(xy) / LATTICE_NODES))))
    cell = np.rint((xy - xy.min(axis=0)) / spacing).astype(np.int64)
    band = taper < FINE
    coarse = np.all(cell % (2 * stride) == 0, axis=1)
    on = np.flatnonzero(np.all(cell % stride == 0, axis=1) & (taper > 0))
    if len(on) == 0:
        return on, scipy.sparse.csr_matrix((0, 0))
    at = cell[on] // stride
    number = -np.ones(at.max(axis=0) + 5, dtype=np.int64)
    number[at[:, 0] + 2, at[:, 1] + 2] = np.arange(len(on))  # two rings of -1 around it
    i, j = at[:, 0] + 2, at[:, 1] + 2
    stencils = (  # (offsets, coefficients) of each second difference
        (((1, 0), (0, 0), (-1, 0)), (1.0, -2.0, 1.0)),
        (((0, 1), (0, 0), (0, -1)), (1.0, -2.0, 1.0)),
        (((1, 1), (-1, -1), (1, -1), (-1, 1)), (0.5, 0.5, -0.5, -0.5)),
    )
    # farther in, a difference over twice the step is four times one over the step, and stands
    # for four of them: weighed by 2 / 4
    levels = ((band[on], 1, 1.0), (~band[on] & coarse[on], 2, 0.5))
    rows, cols, values = [], [], []
    count = 0
    for centre, reach, scale in levels:
        for offsets, coefficients in stencils:
            ids = np.stack([number[i + reach * di, j + reach * dj] for di, dj in offsets])
            full = np.all(ids >= 0, axis=0) & centre
            n = int(full.sum())
            for k, weight in enumerate(coefficients):
                rows.append(count + np.arange(n))
                cols.append(ids[k, full])
                values.append(np.full(n, scale * weight))
            count += n
    reached = np.concatenate(cols)
    used = np.zeros(len(on), dtype=bool)  # the nodes the rows reach, numbered again
    used[reached] = True
    renumbered = np.cumsum(used) - 1
    differences = scipy.sparse.csr_matrix(
        (
            np.concatenate(values).astype(np.float32),
            (np.concatenate(rows), renumbered[reached]),
        ),
        shape=(count, int(used.sum())),
    )
    return on[used], differences


def least_bending(
    bending: Bending,
    start: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    phi: np.ndarray,
    spline: np.ndarray,
) -> np.ndarray:
    """(m,) values in [lo, hi] from `start` for which T · (M + c) bends least on the lattice.

    Parameters
    ----------
    bending : Bending
    start, lo, hi : (m,) float arrays
        The values to start from and their bounds.
    phi : (n, m) float array
        φ(|x − v_j| / ℓ) at the lattice's nodes x for each spline centre v_j.
    spline : (m, m) float array
        The spline's weights per unit value at each vein point (c on the lattice: phi @ spline).

    The normal matrix is formed as Sᵀ (TΦ)ᵀ Dᵀ D (TΦ) S: n m² + 2 m³ products where (D T Φ S)ᵀ
    (D T Φ S) took 3 n m² and a solve of n right-hand sides; in single precision, half the time
    for the same bench_bent rows.
    """
    d = bending.differences
    tphi = (bending.taper[:, None] * phi).astype(np.float32)
    gram = (tphi.T @ np.asarray(d.T @ np.asarray(d @ tphi))).astype(float)
    normal = spline.T @ gram @ spline
    bends = d @ (bending.taper * bending.relief).astype(np.float32)
    shift = spline.T @ (tphi.T @ (d.T @ bends)).astype(float)
    probe = np.ones(len(normal))
    for _ in range(POWER_STEPS):  # the largest eigenvalue (normal is positive semi-definite)
        probe = normal @ probe
        largest = float(np.linalg.norm(probe))
        if not np.isfinite(largest) or largest <= 0:
            return start
        probe /= largest
    largest *= 1.1  # the power steps come from below
    values = previous = ahead = start
    momentum = 1.0
    for _ in range(STEPS):
        values = np.clip(ahead - (normal @ ahead + shift) / largest, lo, hi)
        following = 0.5 * (1 + np.sqrt(1 + 4 * momentum**2))
        ahead = values + (momentum - 1) / following * (values - previous)
        previous, momentum = values, following
    return values
