"""Step 3: the height guide p(x) of section 3.3 (eqs. 4-5), the probability map on the grid.

Between the margin and a vein (eq. 4), p rises linearly from 0 at the nearest boundary point b to
the vein's height h_v at its projection v':

    p(x) = h_v |b − x| / |b − v'|

When the two nearest height constraints are two veins rather than a vein and the margin (parallel
veins), eq. 5 applies. Its printed form is garbled; we use, as agreed in DESIGN.md,

    p(x) = h_v (1 − |v' − x| / (2 |v' − v''|))

with |v' − v''| measured through x (|v' − x| + |x − v''|, equal to it for x between two parallel
veins and never zero where veins meet), so p dips gently between veins, to 3/4 of h_v midway.
Ties among nearest points are averaged, as the paper says. Heights are signed: a vein below the
boundary's plane pulls p below zero.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

TIE = 1e-9  # relative distance under which nearest points count as tied


def _nearest_with_ties(
    tree: cKDTree, xy: np.ndarray, values: np.ndarray, k: int = 4
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distance to the nearest point, and the mean position and value of the tied nearest points."""
    k = min(k, tree.n)
    dist, idx = tree.query(xy, k=k)
    dist, idx = dist.reshape(len(xy), k), idx.reshape(len(xy), k)
    tied = dist <= dist[:, :1] * (1 + TIE) + 1e-15
    count = tied.sum(axis=1)
    pos = (tree.data[idx] * tied[..., None]).sum(axis=1) / count[:, None]
    val = (values[idx] * tied).sum(axis=1) / count
    return dist[:, 0], pos, val


def height_guide(
    xy: np.ndarray,
    boundary: np.ndarray,
    veins: list[np.ndarray],
    heights: list[np.ndarray],
) -> np.ndarray:
    """The guide p at points inside the leaf.

    Parameters
    ----------
    xy : (n, 2) float array
        Query points (grid nodes with g >= 0).
    boundary : (b, 2) float array
        Boundary points in the plane.
    veins : list of (m_i, 2) float arrays
        Vein points projected onto the plane (v'), one array per vein.
    heights : list of (m_i,) float arrays
        Signed heights h_v of the vein points (eq. 3).

    Returns
    -------
    (n,) float array
        p(x); all zeros when there are no veins (a flat leaf).
    """
    xy = np.asarray(xy, dtype=float)
    if not veins:
        return np.zeros(len(xy))
    d_b, b, _ = _nearest_with_ties(cKDTree(boundary), xy, np.zeros(len(boundary)))
    # per vein: distance, nearest (tie-averaged) point and height
    per_vein = [_nearest_with_ties(cKDTree(v), xy, h) for v, h in zip(veins, heights, strict=True)]
    dist = np.column_stack([d for d, _, _ in per_vein])
    order = np.argsort(dist, axis=1)
    rows = np.arange(len(xy))
    first = order[:, 0]
    d_v = dist[rows, first]
    v_pos = np.stack([pos for _, pos, _ in per_vein], axis=1)[rows, first]
    h_v = np.column_stack([h for _, _, h in per_vein])[rows, first]

    # eq. 4: between the margin and the nearest vein
    reach = np.linalg.norm(b - v_pos, axis=1)
    p = h_v * np.clip(d_b / np.maximum(reach, 1e-300), 0.0, 1.0)
    if len(veins) > 1:  # eq. 5: between two veins, when both are nearer than the margin
        d_v2 = dist[rows, order[:, 1]]
        between = d_v2 < d_b
        ratio = d_v / np.maximum(2 * (d_v + d_v2), 1e-300)
        p = np.where(between, h_v * (1 - ratio), p)
    return p
