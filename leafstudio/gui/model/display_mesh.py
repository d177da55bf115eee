"""A lighter mesh for the 3D view when the full one has more triangles than the screen can show.

Software OpenGL (Mesa llvmpipe) spends main-thread time on every vertex of every render, and
uploading a new result costs in proportion to its size: at grid 512 the nested demo has 86k
triangles on a view about 800 pixels across. The view draws a subset of the same vertices
instead, by vertex clustering on the reconstruction grid: the grid nodes are gathered into
blocks of f x f, each block drawn by one of its own nodes (the block's corner where it is
kept), and the triangles re-joined over those; the outline's vertices are all kept, so the
margin is drawn exactly. Every vertex drawn is a vertex of the full mesh with its own height,
curvatures, normal and UV (taken by index), so colours and shading are the full mesh's.

Display only: exports, measurements and "Show mesh edges" use the full mesh. Numpy only (made
on the worker thread, with the rest of the layers).
"""

from __future__ import annotations

import numpy as np

DISPLAY_TRIANGLES = 30_000  # above this many triangles, the view draws a clustered subset
LATTICE_TOLERANCE = 1e-6  # in grid spacings: a vertex this close to a grid node is that node


def display_subset(
    xy: np.ndarray,
    faces: np.ndarray,
    origin: np.ndarray,
    spacing: float,
    outline: np.ndarray,
    max_triangles: int | None = None,
) -> tuple[np.ndarray, np.ndarray] | None:
    """The vertices to draw and their triangles, or None when the mesh is small enough.

    Parameters
    ----------
    xy : (n, 2) float array
        The mesh's vertices on the leaf's plane (the grid's coordinates).
    faces : (m, 3) int array
        Its triangles.
    origin, spacing
        The reconstruction grid: its node (0, 0) and the distance between nodes.
    outline : (n,) bool array
        Which vertices are the outline's (Result.on_outline; a trimmed scan's are not the first
        len(polygon)): each kept.
    max_triangles : int, optional
        The blocks are f x f nodes with f the least whole number that brings the triangles
        near or under this (DISPLAY_TRIANGLES if not given).

    Returns
    -------
    keep : (k,) int array
        Indices of the full mesh's vertices to draw (index every point array with it).
    faces : (l, 3) int array
        Triangles over `keep`'s order, in the full mesh's turning sense, without repeats.
    """
    faces = np.asarray(faces)
    most = DISPLAY_TRIANGLES if max_triangles is None else max_triangles
    f = int(np.ceil(np.sqrt(len(faces) / max(most, 1))))
    if f <= 1 or len(xy) == 0:
        return None
    n = len(xy)
    rel = (np.asarray(xy, float) - np.asarray(origin, float)) / spacing
    ij = np.rint(rel).astype(np.int64)
    on_lattice = (np.abs(rel - ij) < LATTICE_TOLERANCE).all(axis=1)
    outline = np.asarray(outline, dtype=bool)
    if outline.shape != (n,):  # the count it took before exports32 drew no triangle at all
        raise ValueError(
            f"outline must be a ({n},) bool array (Result.on_outline), not {outline.shape}"
        )
    n_outline = int(np.count_nonzero(outline))
    if np.count_nonzero(on_lattice) < (n - n_outline) / 2:
        return None  # not a mesh over this grid (another mesher, other units): drawn whole
    block = ij // f
    block -= block.min(axis=0)
    key = block[:, 1] * (block[:, 0].max() + 1) + block[:, 0] + n_outline
    key[outline] = np.arange(n_outline)  # each outline vertex is a block of its own
    # which vertex draws a block: its corner node first, then other nodes, then points the
    # mesher added along the margin
    rank = np.where(on_lattice, ij[:, 0] % f + ij[:, 1] % f, 2 * f)
    order = np.argsort(key * (2 * f + 1) + rank, kind="stable")
    sorted_keys = key[order]
    first = np.ones(n, dtype=bool)
    np.not_equal(sorted_keys[1:], sorted_keys[:-1], out=first[1:])
    keep = order[first]
    drawn_by = np.empty(n, dtype=np.int64)
    drawn_by[order] = np.cumsum(first) - 1
    tri = drawn_by[faces]
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    tri = tri[(a != b) & (b != c) & (a != c)]
    corners = np.sort(tri, axis=1)
    k = len(keep)
    code = (corners[:, 0] * k + corners[:, 1]) * k + corners[:, 2]
    _, unique = np.unique(code, return_index=True)
    return keep, tri[np.sort(unique)]
