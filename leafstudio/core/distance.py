"""Exact distances from points to a triangle mesh, without holding the GIL for long.

open3d's raycasting scene did this before, but it held the GIL while building its BVH (about
100 ms for a grid-512 mesh), so the app's window froze while the worker measured a result; and
importing open3d takes seconds and 250 MB. Here scipy's k-d tree (which releases the GIL) finds
each point's nearest vertex, whose distance bounds the answer: the nearest triangle then has a
vertex within that bound plus the longest edge, and a compiled loop (nogil) measures exactly the
triangles around those vertices.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy.spatial import cKDTree

from leafstudio.core.buckets import kernel_array


def mesh_distances(vertices: np.ndarray, triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(n,) distance from each of the (n, 3) points to the nearest point of the (m, 3) triangles
    over the (v, 3) vertices (to the nearest vertex when there are no triangles)."""
    points = kernel_array(np.asarray(points, dtype=float).reshape(-1, 3))
    vertices = kernel_array(vertices)
    triangles = kernel_array(np.asarray(triangles).reshape(-1, 3), np.int64)
    if len(points) == 0:
        return np.zeros(0)
    if len(triangles) == 0:
        if len(vertices) == 0:
            return np.full(len(points), np.inf)
        return cKDTree(vertices).query(points)[0]
    first, triangle_of, longest = _incidence(vertices, triangles)
    used = np.flatnonzero(np.diff(first))  # a vertex of no triangle bounds nothing
    # an unbalanced tree builds in half the time and answers these few queries as fast
    tree = cKDTree(vertices[used], balanced_tree=False, compact_nodes=False)
    bound, _ = tree.query(points)
    near = tree.query_ball_point(points, bound + longest * (1 + 1e-9) + 1e-12)
    sizes = np.fromiter((len(n) for n in near), np.int64, len(near))
    starts = np.concatenate([[0], np.cumsum(sizes)])
    candidates = used[np.concatenate([np.asarray(n, np.int64) for n in near])]
    return _nearest(points, vertices, triangles, starts, candidates, first, triangle_of, bound)


@njit(cache=True, nogil=True)
def _incidence(vertices, triangles):
    """Each vertex's triangles as a CSR list (first (v + 1,), triangle_of (3 m,)), by a counting
    sort, and the length of the longest edge."""
    first = np.zeros(len(vertices) + 1, np.int64)
    longest = 0.0
    for t in range(len(triangles)):
        for k in range(3):
            first[triangles[t, k] + 1] += 1
            a, b = vertices[triangles[t, k]], vertices[triangles[t, (k + 1) % 3]]
            longest = max(longest, _sq(a[0] - b[0], a[1] - b[1], a[2] - b[2]))
    for v in range(len(vertices)):
        first[v + 1] += first[v]
    fill = first[:-1].copy()
    triangle_of = np.empty(3 * len(triangles), np.int64)
    for t in range(len(triangles)):
        for k in range(3):
            v = triangles[t, k]
            triangle_of[fill[v]] = t
            fill[v] += 1
    return first, triangle_of, np.sqrt(longest)


@njit(cache=True, nogil=True)
def _nearest(points, vertices, triangles, starts, candidates, first, triangle_of, bound):
    out = np.empty(len(points))
    for i in range(len(points)):
        px, py, pz = points[i, 0], points[i, 1], points[i, 2]
        best = bound[i] * bound[i]
        for s in range(starts[i], starts[i + 1]):
            v = candidates[s]
            for k in range(first[v], first[v + 1]):
                corner = triangles[triangle_of[k]]
                a, b, c = vertices[corner[0]], vertices[corner[1]], vertices[corner[2]]
                best = min(best, _triangle_sq(px, py, pz, a, b, c))
        out[i] = np.sqrt(best)
    return out


@njit(cache=True, nogil=True)
def _triangle_sq(px, py, pz, a, b, c):
    """Squared distance from p to triangle abc (Ericson, Real-Time Collision Detection, 5.1.5:
    the Voronoi regions of the corners, then of the edges, then the face), in scalars."""
    abx, aby, abz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    acx, acy, acz = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    apx, apy, apz = px - a[0], py - a[1], pz - a[2]
    bpx, bpy, bpz = px - b[0], py - b[1], pz - b[2]
    area2 = _sq(aby * acz - abz * acy, abz * acx - abx * acz, abx * acy - aby * acx)
    if area2 <= 1e-24 * _sq(abx, aby, abz) * _sq(acx, acy, acz):  # flat: its nearest edge
        return min(
            _segment_sq(apx, apy, apz, abx, aby, abz),
            _segment_sq(apx, apy, apz, acx, acy, acz),
            _segment_sq(bpx, bpy, bpz, c[0] - b[0], c[1] - b[1], c[2] - b[2]),
        )
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0 and d2 <= 0:
        return _sq(apx, apy, apz)
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0 and d4 <= d3:
        return _sq(bpx, bpy, bpz)
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        v = d1 / (d1 - d3)
        return _sq(apx - v * abx, apy - v * aby, apz - v * abz)
    cpx, cpy, cpz = px - c[0], py - c[1], pz - c[2]
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0 and d5 <= d6:
        return _sq(cpx, cpy, cpz)
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        w = d2 / (d2 - d6)
        return _sq(apx - w * acx, apy - w * acy, apz - w * acz)
    va = d3 * d6 - d5 * d4
    if va <= 0 and d4 - d3 >= 0 and d5 - d6 >= 0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return _sq(bpx - w * (c[0] - b[0]), bpy - w * (c[1] - b[1]), bpz - w * (c[2] - b[2]))
    total = va + vb + vc
    v, w = vb / total, vc / total
    return _sq(apx - v * abx - w * acx, apy - v * aby - w * acy, apz - v * abz - w * acz)


@njit(cache=True, nogil=True)
def _segment_sq(rx, ry, rz, ex, ey, ez):
    """Squared distance from a point at r from a segment's start to the segment of vector e."""
    length2 = ex * ex + ey * ey + ez * ez
    t = 0.0 if length2 <= 0 else min(max((rx * ex + ry * ey + rz * ez) / length2, 0.0), 1.0)
    return _sq(rx - t * ex, ry - t * ey, rz - t * ez)


@njit(cache=True, nogil=True)
def _sq(x, y, z):
    return x * x + y * y + z * z
