"""The vein correction's derivatives at the mesh's grid nodes, by finite differences of its
values there (correct.py: c at every node inside the leaf is known already, from its lattice).

The mesh's curvature arrays need ∇c and ∇²c at every vertex. In closed form (kelvin.
spline_derivatives) that is every vertex against every spline centre: at grid 512 (111,687
nodes, 200 centres) 232 ms, more than the rest of the run (the pipeline without the correction
took 143 ms; at grid 128, 14.5 of a flat ovate's 51 ms). Most vertices are grid
nodes, where c is known, so the second-order central differences there cost only one compiled
loop of arithmetic; the outline's points and the few added in the margin band keep the closed form.

c is smooth on the grid's scale except at its centres, where its Hessian has a log r spike
(−kei(r/ℓ) ~ r² log r: the closed form reads it no nearer than correct.HESSIAN_CUT of the length,
so ∇²c reached 21 on a gallery ovate, ten times the mixture's largest Hessian, at nodes a hair
from a vein point). The differences read c over one grid step, as the mesh's
own triangles do: away from the centres they agree with the closed form to a few parts in 1e4
of its largest Hessian at grid 128 (1.6e-5 at grid 512, the median), and beside a centre they
give the curvature the mesh can show rather than the spike.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from leafstudio.core.grid import Grid
from leafstudio.core.jit import njit


def _around(asked: np.ndarray) -> np.ndarray:
    """The (ny, nx) bool `asked` grown by one node each way, diagonals too: the 3 x 3 blocks the
    differences read, as two passes of shifted ors (scipy.ndimage.binary_dilation with a 3 x 3
    block, the same nodes: 0.083 -> 0.011 ms on a 131 x 100 grid, best of 200)."""
    rows = asked.copy()
    rows[1:] |= asked[:-1]
    rows[:-1] |= asked[1:]
    out = rows.copy()
    out[:, 1:] |= rows[:, :-1]
    out[:, :-1] |= rows[:, 1:]
    return out


def node_derivatives(
    value: Callable[[np.ndarray], np.ndarray],
    grid: Grid,
    known: np.ndarray,
    known_values: np.ndarray,
    nodes: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """c (n,), ∇c (n, 2) and ∇²c (n, 2, 2) at the grid's `nodes` ((n,) flat indices), by
    central differences of c over one grid step.

    Parameters
    ----------
    value : callable
        c at (k, 2) plane points: asked for the stencil's nodes where c is not known (outside
        the leaf, one step past the margin).
    grid : Grid
    known : (ny * nx,) bool array
        The nodes where c is known (inside the leaf).
    known_values : (count of known,) float array
        c there, in grid order.
    nodes : (n,) int array
        Flat indices of the nodes asked for.

    Returns
    -------
    The three arrays, or None when a node's stencil runs off the grid (a leaf filling it to its
    edge: the caller takes the closed form).
    """
    ny, nx = grid.shape
    flat = np.asarray(nodes, dtype=np.int64)
    row, col = np.divmod(flat, nx)
    if len(nodes) and (row.min() < 1 or col.min() < 1 or row.max() > ny - 2 or col.max() > nx - 2):
        return None
    c = np.full(ny * nx, np.nan)
    c[known] = known_values
    asked = np.zeros((ny, nx), dtype=bool)
    asked[row, col] = True  # its stencil's nodes: the 3 x 3 block around each (np.unique of
    # their indices took 60 ms at grid 512)
    missing = np.flatnonzero(_around(asked).ravel() & ~known)
    if len(missing):
        c[missing] = value(grid.points[missing])
    h = grid.spacing
    return _differences(c, flat, nx, 2 * h, h**2, 4 * h * h)


@njit(cache=True, nogil=True)
def _differences(c, flat, nx, two_h, h2, four_h2):
    """c, its central first differences over `two_h` and second over `h2` (the cross one over
    `four_h2`) at the (n,) flat indices `flat` of the grid's (ny * nx,) values `c`, a node at a
    time (numpy's nine reads of every node's neighbours by flat index and its arithmetic over
    whole arrays: node_derivatives 0.31 -> 0.22 ms on a flat ovate at grid 128, 6,900 nodes,
    this kernel 0.044, best of 60, two pairs; the same expressions in the same order, the mesh's
    curvatures the same to the bit)."""
    n = len(flat)
    middle = np.empty(n)
    gradient = np.empty((n, 2))
    hessian = np.empty((n, 2, 2))
    for i in range(n):
        f = flat[i]
        mid = c[f]
        east, west, north, south = c[f + 1], c[f - 1], c[f + nx], c[f - nx]
        middle[i] = mid
        gradient[i, 0] = (east - west) / two_h
        gradient[i, 1] = (north - south) / two_h
        hessian[i, 0, 0] = (east - 2 * mid + west) / h2
        hessian[i, 1, 1] = (north - 2 * mid + south) / h2
        cross = c[f + nx + 1] - c[f + nx - 1] - c[f - nx + 1] + c[f - nx - 1]
        hessian[i, 0, 1] = hessian[i, 1, 0] = cross / four_h2
    return middle, gradient, hessian
