"""The vein correction's values chosen for the whole surface's bending (issue 21, item 4).

correct.py brings the height surface onto the vein points with a spline c, each value c(v_i)
free within a tolerance. Chosen so that c alone bends least (`correct._within`), the surface
through the veins still creased more than the paper's pure GMM surface on some rows of
`bench_bent.py --veins` (99th-percentile dihedral: deltoid's margin band 2.35° against 2.19°, a
drawn leaf's 8.54° against 8.32°, linear's 7.81° against 7.78°): c bent least where the mixture
bent most. Here the values are chosen within the same tolerances so that the surface itself,
z = T · (M + c) over the grid's nodes inside the leaf, bends least: the sum of its squared second
differences (xx, yy and the cross difference) on a lattice of the nodes STRIDE-d to about
LATTICE_NODES. c is linear in its values (the spline's weights are one solve of them), so this is
a small quadratic program in the values, box-constrained, solved by projected gradient steps
(FISTA) from the values `_within` found. The margin band's 99th-percentile dihedral falls below
the paper's surface on every gallery form (lanceolate 3.17° -> 1.67°, deltoid 2.19° -> 1.87°).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse

LATTICE_NODES = 2500  # grid nodes, about, on the lattice whose bending is summed
STEPS = 50  # projected gradient steps (100: the same bench_bent --veins rows, 0.01° apart)


@dataclass(frozen=True)
class Bending:
    """The lattice over which the surface's bending is summed: its nodes, T(g/δ) and the
    mixture's relief M there, and the (r, n) sparse second differences between them."""

    xy: np.ndarray  # (n, 2) lattice nodes in the plane
    taper: np.ndarray  # (n,) T(g/δ)
    relief: np.ndarray  # (n,) M, the mixture alone
    differences: scipy.sparse.csr_matrix  # (r, n)


def lattice(xy: np.ndarray, taper: np.ndarray) -> tuple[np.ndarray, scipy.sparse.csr_matrix]:
    """Indices of the (n, 2) grid nodes `xy` on every STRIDE-th row and column (STRIDE so that
    about LATTICE_NODES are kept) and the second differences between them: (rows, kept) sparse,
    one row per direction (x, y, and the cross difference) wherever all its nodes are kept."""
    unique = np.unique(xy[:, 0])
    spacing = float(np.min(np.diff(unique))) if len(unique) > 1 else 1.0
    stride = max(1, round(float(np.sqrt(len(xy) / LATTICE_NODES))))
    cell = np.rint((xy - xy.min(axis=0)) / spacing).astype(np.int64)
    on = np.flatnonzero(np.all(cell % stride == 0, axis=1) & (taper > 0))
    if len(on) == 0:
        return on, scipy.sparse.csr_matrix((0, 0))
    at = cell[on] // stride
    number = -np.ones(at.max(axis=0) + 3, dtype=np.int64)
    number[at[:, 0] + 1, at[:, 1] + 1] = np.arange(len(on))  # a ring of -1 around the lattice
    i, j = at[:, 0] + 1, at[:, 1] + 1
    stencils = (  # (offsets, coefficients) of each second difference
        (((1, 0), (0, 0), (-1, 0)), (1.0, -2.0, 1.0)),
        (((0, 1), (0, 0), (0, -1)), (1.0, -2.0, 1.0)),
        (((1, 1), (-1, -1), (1, -1), (-1, 1)), (0.5, 0.5, -0.5, -0.5)),
    )
    rows, cols, values = [], [], []
    count = 0
    for offsets, coefficients in stencils:
        ids = np.stack([number[i + di, j + dj] for di, dj in offsets])
        full = np.all(ids >= 0, axis=0)
        n = int(full.sum())
        for k, weight in enumerate(coefficients):
            rows.append(count + np.arange(n))
            cols.append(ids[k, full])
            values.append(np.full(n, weight))
        count += n
    differences = scipy.sparse.csr_matrix(
        (np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))),
        shape=(count, len(on)),
    )
    return on, differences


def least_bending(
    bending: Bending,
    start: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    to_lattice: np.ndarray,
) -> np.ndarray:
    """(m,) values in [lo, hi] from `start` for which T · (M + c) bends least on the lattice.

    Parameters
    ----------
    bending : Bending
    start, lo, hi : (m,) float arrays
        The values to start from and their bounds.
    to_lattice : (n, m) float array
        c on the lattice's nodes per unit value at each vein point.
    """
    d = bending.differences
    a = np.asarray(d @ (bending.taper[:, None] * to_lattice))  # (r, m): bends per unit value
    b = d @ (bending.taper * bending.relief)  # the mixture's own bends
    normal, shift = a.T @ a, a.T @ b
    largest = float(np.linalg.eigvalsh(normal)[-1])
    if not np.isfinite(largest) or largest <= 0:
        return start
    values = previous = ahead = start
    momentum = 1.0
    for _ in range(STEPS):
        values = np.clip(ahead - (normal @ ahead + shift) / largest, lo, hi)
        following = 0.5 * (1 + np.sqrt(1 + 4 * momentum**2))
        ahead = values + (momentum - 1) / following * (values - previous)
        previous, momentum = values, following
    return values
