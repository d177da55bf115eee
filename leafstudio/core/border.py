"""A triangle mesh's border: its edges counted (how many triangles share each), its boundary
loops and connected pieces, and the length of its margin, the loops that bound each piece from
outside (evaluate.py's mesh facts and perimeter)."""

from __future__ import annotations

import numpy as np

from leafstudio.core.edges import edge_table
from leafstudio.core.kernels import ensure_compiled


def edge_counts(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unique undirected edges (e, 2), each (low, high) and in that order, and how many
    triangles share each (edges.edge_table)."""
    ensure_compiled()
    return edge_table(triangles)[:2]


def count_border_loops(
    triangles: np.ndarray, counted: tuple[np.ndarray, np.ndarray] | None = None
) -> int:
    """Number of closed loops formed by the edges that belong to one triangle only (`counted`:
    the triangles' edge_counts, when they are known already)."""
    edges, counts = counted if counted is not None else edge_counts(triangles)
    border = edges[counts == 1]
    if len(border) == 0:
        return 0
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    nodes, inverse = np.unique(border, return_inverse=True)
    inverse = inverse.reshape(-1, 2)
    graph = coo_matrix(
        (np.ones(len(border)), (inverse[:, 0], inverse[:, 1])), shape=(len(nodes),) * 2
    )
    return int(connected_components(graph, directed=False)[0])


def connected_pieces(triangles: np.ndarray, edges: np.ndarray | None = None) -> int:
    """Number of edge-connected components of the triangles (`edges`: their unique edges, as
    edge_counts gives them, when they are known already)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = int(triangles.max(initial=-1)) + 1
    used = np.zeros(n, bool)
    used[triangles.ravel()] = True  # vertices no triangle uses are components of their own
    if edges is None:
        edges = np.column_stack([triangles.ravel(), triangles[:, [1, 2, 0]].ravel()])
    ones = np.ones(len(edges), np.int8)
    graph = coo_matrix((ones, (edges[:, 0], edges[:, 1])), shape=(n, n))
    return int(connected_components(graph, directed=False)[0]) - int(n - used.sum())


def margin_length(
    points: np.ndarray,
    triangles: np.ndarray,
    flat_xy: np.ndarray,
    counted: tuple[np.ndarray, np.ndarray] | None = None,
) -> float:
    """The 3D length of the mesh's margin: the boundary loops that bound each of its pieces from
    outside. A piece's leftmost point on its flat blade lies on its outer loop (a hole is
    enclosed by the blade), so each piece's outer loop is the one through its border vertex of
    least `flat_xy` x; its other loops are holes, not counted (and so are a ball-pivoting mesh's
    pinholes). No walk along the loops: their edges' lengths are summed by loop (a grid-256
    ovate form's 55,600 faces in 2.5 ms, 1.9 of them the edge count; a grid-128's 0.8).

    Parameters
    ----------
    points : (n, 3) float array
        The mesh's vertices as it is (bent, for a bent leaf).
    triangles : (m, 3) int array
        Its triangles.
    flat_xy : (n, 2) float array
        The same vertices on the flat blade (Result.mesh_on_blade; a flat mesh's in its plane),
        where the blade does not overlap itself as a rolled tube seen from the side does.
    counted : tuple of (e, 2) int array and (e,) int array, optional
        The triangles' edge_counts, when they are known already.

    Returns
    -------
    float
        The outer loops' total length (0 for a closed mesh or no triangles).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    edges, counts = counted if counted is not None else edge_counts(triangles)
    border = edges[counts == 1]
    if not len(border):
        return 0.0
    n = len(points)

    def labels(pairs: np.ndarray) -> np.ndarray:  # each vertex's component through `pairs`
        ones = np.ones(len(pairs), np.int8)
        graph = coo_matrix((ones, (pairs[:, 0], pairs[:, 1])), shape=(n, n))
        return connected_components(graph, directed=False)[1]

    steps = np.linalg.norm(points[border[:, 0]] - points[border[:, 1]], axis=1)
    vertex_loop = labels(border)
    loop = vertex_loop[border[:, 0]]  # each border edge's
    if np.all(loop == loop[0]):  # one loop: the margin (a form's, 7 of the 8 scans')
        return float(steps.sum())
    piece = labels(edges)
    on = np.unique(border)
    on = on[np.lexsort((flat_xy[on, 0], piece[on]))]  # by piece, leftmost first
    leftmost = on[np.r_[True, piece[on[1:]] != piece[on[:-1]]]]
    return float(steps[np.isin(loop, vertex_loop[leftmost])].sum())
